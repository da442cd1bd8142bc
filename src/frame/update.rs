//! Changing a built [`Frame`] in place: the parameters that live in uniforms or small
//! buffers (wind, hair colour, lights, shading) are written where they live, so a
//! slider does not pay for a new frame (uploads, root sampling, pipelines).

use glam::Vec3;
use pelage_scene::{
    DynamicsParams, HairParams, Light, MeshMotion, Scene, ShadeParams, ShadowParams, SkinBend,
    WindParams,
};

use super::Frame;

/// What a frame was built from, as far as an in-place update must compare it (the
/// lights are the frame's own).
#[derive(Clone, Debug)]
pub(crate) struct Built {
    hair: HairParams,
    shadow: ShadowParams,
    shade: ShadeParams,
    dynamics: Option<DynamicsParams>,
    motion: Option<MeshMotion>,
    skin: Option<SkinBend>,
    /// [`geometry_fingerprint`] of the mesh and the groom.
    geometry: u64,
}

impl Built {
    /// What `scene` builds.
    pub(crate) fn of(scene: &Scene) -> Self {
        Self {
            hair: scene.hair.clone(),
            shadow: scene.shadow.clone(),
            shade: scene.shade.clone(),
            dynamics: scene.dynamics.clone(),
            motion: scene.motion.clone(),
            skin: scene.skin.clone(),
            geometry: geometry_fingerprint(scene),
        }
    }
}

/// `hair` without the parts [`Frame::update`] changes in place.
fn structural(hair: &HairParams) -> HairParams {
    let mut out = hair.clone();
    out.wind = WindParams::default();
    out.growth.color = Vec3::ZERO;
    out.growth.color_jitter = 0.0;
    out
}

/// A 64-bit hash of every number of the scene's mesh, groom and guides (a mixing hash over the
/// bit patterns: a changed vertex changes it).
fn geometry_fingerprint(scene: &Scene) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    let mut add = |w: u32| h = (h.rotate_left(5) ^ u64::from(w)).wrapping_mul(0x0100_0000_01b3);
    let mut vecs = |v: &[Vec3]| {
        add(v.len() as u32);
        v.iter()
            .flat_map(|p| p.to_array())
            .for_each(|f| add(f.to_bits()))
    };
    vecs(&scene.mesh.positions);
    vecs(&scene.mesh.normals);
    let mut add = |w: u32| h = (h.rotate_left(5) ^ u64::from(w)).wrapping_mul(0x0100_0000_01b3);
    add(scene.mesh.indices.len() as u32);
    scene.mesh.indices.iter().for_each(|&i| add(i));
    match &scene.groom {
        None => add(0),
        Some(g) => {
            add(1);
            add(g.segments);
            add(g.strands);
            add(g.skipped);
            g.source_strands.iter().for_each(|&i| add(i));
            match &g.widths {
                None => add(0),
                Some(w) => {
                    add(w.len() as u32);
                    w.iter().for_each(|f| add(f.to_bits()));
                }
            }
            add(g.points.len() as u32);
            g.points
                .iter()
                .flat_map(|p| p.to_array())
                .for_each(|f| add(f.to_bits()));
        }
    }
    match &scene.guides {
        None => add(0),
        Some(p) => {
            add(1);
            [p.strands, p.k].into_iter().for_each(&mut add);
            [p.clump, p.noise, p.max_root_distance]
                .into_iter()
                .for_each(|f| add(f.to_bits()));
        }
    }
    h
}

/// The facade's error for a change that needs a new frame.
fn rebuild(what: impl Into<String>) -> crate::Error {
    crate::Error::NeedsRebuild(what.into())
}

impl Frame {
    /// Applies what changed between the scene the frame was built from (or last updated
    /// to) and `scene` in place when every change lives in uniforms or small buffers: the
    /// wind, the hair colour and its jitter (stage 1's roots are rewritten, bit for bit
    /// the colours a new frame samples), the lights when their count stays
    /// ([`Frame::set_lights`]) and the shading parameters (background, mesh colour,
    /// ambient, root occlusion, the shading model's parameters; Marschner's and Chiang's
    /// tables are filled again when what they tabulate changed: one compute submission,
    /// waited for). The next frame is then the one a new frame of `scene` draws
    /// (`tests/update.rs` compares them).
    ///
    /// Anything else (the mesh or groom, strand count, growth other than colour, level of
    /// detail parameters, the shadow method or its parameters, the light count with
    /// shadows on, the transparency method, sample count, minimum ribbon width, the kind
    /// of shading model, a groom's reach under a new wind, the dynamics, the motion, the
    /// skin) is [`Error::NeedsRebuild`](crate::Error::NeedsRebuild) naming it: build a
    /// new frame (or [`Renderer`](crate::Renderer)) for that scene. Bad values are an
    /// error, as from [`Frame::new`]. On any error nothing is applied. The camera is the
    /// caller's at every prepare and is not compared.
    pub fn update(&mut self, gpu: &pelage_gpu::Gpu, scene: &Scene) -> crate::Result<()> {
        // Validate first: a refused value changes nothing.
        scene.hair.wind.validate()?;
        scene.hair.growth.validate()?;
        Light::validate_all(&scene.lights)?;
        scene.shade.validate()?;
        // Lights the shadows cannot aim at (a point light at the hair's centre) are
        // refused here, before anything is applied (set_lights, last, checks it again).
        for (i, light) in scene.lights.iter().enumerate() {
            light.shadow_light(i, self.shadow_target)?;
        }
        let built = &self.built;
        if geometry_fingerprint(scene) != built.geometry {
            return Err(rebuild("the mesh or the groom"));
        }
        let (old, new) = (structural(&built.hair), structural(&scene.hair));
        if old != new {
            return Err(rebuild(if old.roots != new.roots {
                "hair.roots"
            } else if old.growth != new.growth {
                "hair.growth (other than its colour)"
            } else {
                "hair.lod"
            }));
        }
        if scene.shadow != built.shadow {
            return Err(rebuild("shadow"));
        }
        if scene.dynamics != built.dynamics {
            return Err(rebuild("dynamics"));
        }
        if scene.motion != built.motion {
            return Err(rebuild("motion"));
        }
        if scene.skin != built.skin {
            return Err(rebuild("skin"));
        }
        self.lights_in_place(&scene.lights).map_err(rebuild)?;
        let wind_changed = scene.hair.wind != built.hair.wind;
        if wind_changed {
            self.wind_in_place(&scene.hair.wind)?.map_err(rebuild)?;
        }
        // Shading last among the checks: the one that may still refuse (the model's kind,
        // the transparency method), changing nothing when it does.
        if scene.shade != self.built.shade {
            match self.hair.set_params(gpu, &scene.shade) {
                Ok(()) => {}
                Err(pelage_shade::ShadeError::NeedsRebuild(why)) => return Err(rebuild(why)),
                Err(e) => return Err(e.into()),
            }
            self.built.shade = scene.shade.clone();
        }
        if wind_changed {
            self.strands.set_wind(scene.hair.wind.clone())?;
            self.built.hair.wind = scene.hair.wind.clone();
        }
        let g = &scene.hair.growth;
        let built = &self.built.hair.growth;
        if (g.color, g.color_jitter) != (built.color, built.color_jitter) {
            self.strands
                .set_color(&gpu.queue, g.color, g.color_jitter)?;
            self.built.hair.growth.color = g.color;
            self.built.hair.growth.color_jitter = g.color_jitter;
        }
        if scene.lights != self.lights {
            self.set_lights(&scene.lights)?;
        }
        Ok(())
    }

    /// `Ok(Err(why))` when `wind` changes the strands' reach, which sized the later stages.
    fn wind_in_place(&self, wind: &WindParams) -> crate::Result<Result<(), String>> {
        let reach = self.strands.reach_with_wind(wind)?;
        Ok(if reach == self.strands.buffers().reach {
            Ok(())
        } else {
            Err("hair.wind (it changes how far the groom can swing, which sizes the shadows and the level of detail)".into())
        })
    }
}
