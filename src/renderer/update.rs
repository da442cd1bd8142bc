//! Changing a built [`Renderer`] in place: the parameters that live in uniforms or small
//! buffers (wind, hair colour, lights, shading) are written where they live, so a
//! slider does not pay for a new renderer (uploads, root sampling, pipelines).

use glam::Vec3;
use pelage_scene::{
    DynamicsParams, HairParams, Light, MeshMotion, ShadeParams, ShadowParams, SkinBend, WindParams,
};

use super::{Renderer, Scene};

/// What [`Renderer::update`] did with a scene.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Update {
    /// Every change was applied in place; lists what changed (empty: nothing did). The
    /// next frame is the one a new renderer of the scene would draw.
    Applied(Vec<Change>),
    /// A change needs a new renderer (it shapes buffers, passes or pipelines); the
    /// string names the parameter. Nothing was applied: build a [`Renderer`] for the scene.
    Rebuild(String),
}

/// A part of the scene [`Renderer::update`] can change in place.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Change {
    /// `hair.wind` (stage 1's uniforms; [`Renderer::set_wind`]).
    Wind,
    /// `hair.growth.color` and `color_jitter` (the strands' roots;
    /// [`Renderer::set_hair_color`]).
    HairColor,
    /// The lights, same count (stage 3's frame uniforms; [`Renderer::set_lights`]).
    Lights,
    /// Shading parameters in uniforms or tables ([`Renderer::set_shading`]).
    Shading,
}

/// What a renderer was built from, as far as an in-place update must compare it.
#[derive(Clone, Debug)]
pub(crate) struct Built {
    hair: HairParams,
    shadow: ShadowParams,
    shade: ShadeParams,
    lights: Vec<Light>,
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
            lights: scene.lights.clone(),
            dynamics: scene.dynamics.clone(),
            motion: scene.motion.clone(),
            skin: scene.skin.clone(),
            geometry: geometry_fingerprint(scene),
        }
    }
}

/// `hair` without the parts [`Renderer::update`] changes in place.
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

/// The facade's error for a change that needs a new renderer.
fn rebuild(what: impl Into<String>) -> crate::Error {
    crate::Error::NeedsRebuild(what.into())
}

impl Renderer {
    /// Applies what changed between the scene the renderer draws and `scene` in place
    /// when every change lives in uniforms or small buffers: the wind
    /// ([`Renderer::set_wind`]), the hair colour and its jitter
    /// ([`Renderer::set_hair_color`]), the lights when their count stays
    /// ([`Renderer::set_lights`]) and the shading parameters ([`Renderer::set_shading`]:
    /// background, mesh colour, ambient, root occlusion, the shading model's parameters).
    /// The next frame is then the one a new renderer of `scene` draws (`tests/update.rs`
    /// compares them).
    ///
    /// Anything else (the mesh or groom, strand count, growth other than colour, level of
    /// detail parameters, the shadow method or its parameters, the light count with
    /// shadows on, the transparency method, sample count, minimum ribbon width, the kind
    /// of shading model, a groom's reach under a new wind, the dynamics, the motion, the skin) answers [`Update::Rebuild`]
    /// naming it, and nothing is applied. Bad values are an error, as from
    /// [`Renderer::new`], and nothing is applied either. The camera is the caller's at
    /// every `render` and is not compared.
    pub fn update(&mut self, gpu: &pelage_gpu::Gpu, scene: &Scene) -> crate::Result<Update> {
        // Validate first: a refused value changes nothing.
        scene.hair.wind.validate()?;
        scene.hair.growth.validate()?;
        Light::validate_all(&scene.lights)?;
        scene.shade.validate()?;
        let built = &self.built;
        if geometry_fingerprint(scene) != built.geometry {
            return Ok(Update::Rebuild("the mesh or the groom".into()));
        }
        let (old, new) = (structural(&built.hair), structural(&scene.hair));
        if old != new {
            let what = if old.roots != new.roots {
                "hair.roots"
            } else if old.growth != new.growth {
                "hair.growth (other than its colour)"
            } else {
                "hair.lod"
            };
            return Ok(Update::Rebuild(what.into()));
        }
        if scene.shadow != built.shadow {
            return Ok(Update::Rebuild("shadow".into()));
        }
        if scene.dynamics != built.dynamics {
            return Ok(Update::Rebuild("dynamics".into()));
        }
        if scene.motion != built.motion {
            return Ok(Update::Rebuild("motion".into()));
        }
        if scene.skin != built.skin {
            return Ok(Update::Rebuild("skin".into()));
        }
        if let Err(why) = self.frame.lights_in_place(&scene.lights) {
            return Ok(Update::Rebuild(why));
        }
        let wind_changed = scene.hair.wind != built.hair.wind;
        if wind_changed {
            if let Err(why) = self.wind_in_place(&scene.hair.wind)? {
                return Ok(Update::Rebuild(why));
            }
        }
        let mut changes = Vec::new();
        // Shading last among the checks: the one that may still refuse (the model's kind,
        // the transparency method), changing nothing when it does.
        if scene.shade != built.shade {
            match self.set_shading(gpu, &scene.shade) {
                Ok(()) => changes.push(Change::Shading),
                Err(crate::Error::NeedsRebuild(why)) => return Ok(Update::Rebuild(why)),
                Err(e) => return Err(e),
            }
        }
        if wind_changed {
            self.set_wind(scene.hair.wind.clone())?;
            changes.push(Change::Wind);
        }
        let g = &scene.hair.growth;
        if (g.color, g.color_jitter)
            != (
                self.built.hair.growth.color,
                self.built.hair.growth.color_jitter,
            )
        {
            self.set_hair_color(gpu, g.color, g.color_jitter)?;
            changes.push(Change::HairColor);
        }
        if scene.lights != self.built.lights {
            self.set_lights(&scene.lights)?;
            changes.push(Change::Lights);
        }
        Ok(Update::Applied(changes))
    }

    /// Replaces the wind from the next frame on (stage 1's uniforms). Errors: a bad
    /// value; [`Error::NeedsRebuild`](crate::Error::NeedsRebuild) for a groom whose
    /// reach (how far the wind can swing it, which sizes the shadows and the level of
    /// detail) the new wind changes. Nothing changes on an error.
    pub fn set_wind(&mut self, wind: WindParams) -> crate::Result<()> {
        self.wind_in_place(&wind)?.map_err(rebuild)?;
        self.frame.strands_mut().set_wind(wind.clone())?;
        self.built.hair.wind = wind;
        Ok(())
    }

    /// Recolours the hair: every strand's colour becomes `color` times its own
    /// brightness draw (`1 ± color_jitter`), bit for bit the colours a new renderer with
    /// `hair.growth.color = color` and `color_jitter` samples (stage 1's roots are
    /// rewritten: 48 bytes a strand, no shader or pipeline changes). Errors on a negative
    /// or non-finite colour or a jitter outside [0, 1), changing nothing.
    pub fn set_hair_color(
        &mut self,
        gpu: &pelage_gpu::Gpu,
        color: Vec3,
        color_jitter: f32,
    ) -> crate::Result<()> {
        self.frame
            .strands_mut()
            .set_color(&gpu.queue, color, color_jitter)?;
        self.built.hair.growth.color = color;
        self.built.hair.growth.color_jitter = color_jitter;
        Ok(())
    }

    /// Replaces the lights from the next frame on (stage 3's frame uniforms; each light's
    /// shadow follows it). The count must stay the one the renderer was built with while
    /// a shadow method is on (each light has its own shadow passes and a share of the
    /// visibility buffer): another count is
    /// [`Error::NeedsRebuild`](crate::Error::NeedsRebuild). Without shadows any count
    /// from 1 to 4 is taken. Bad lights are an error. Nothing changes on an error.
    pub fn set_lights(&mut self, lights: &[Light]) -> crate::Result<()> {
        self.frame.set_lights(lights)?;
        self.built.lights = lights.to_vec();
        Ok(())
    }

    /// Takes stage 3's parameters that live in uniforms or tables from the next frame on:
    /// background, mesh colour, ambient, root occlusion, and the shading model's
    /// parameters when the model stays the same kind (Marschner's lookup tables and
    /// Chiang's tables are filled again when what they tabulate changed: one compute
    /// submission, waited for). Another transparency method, sample count, minimum
    /// ribbon width, kind of model (Kajiya-Kay to Marschner, analytic to tables) or a
    /// Marschner fibre turning from circular to elliptical under tables is
    /// [`Error::NeedsRebuild`](crate::Error::NeedsRebuild); bad values are an error.
    /// Nothing changes on an error.
    pub fn set_shading(&mut self, gpu: &pelage_gpu::Gpu, shade: &ShadeParams) -> crate::Result<()> {
        match self.frame.hair_pass_mut().set_params(gpu, shade) {
            Ok(()) => {}
            Err(pelage_shade::ShadeError::NeedsRebuild(why)) => return Err(rebuild(why)),
            Err(e) => return Err(e.into()),
        }
        self.built.shade = shade.clone();
        Ok(())
    }

    /// `Ok(Err(why))` when `wind` changes the strands' reach, which sized the later stages.
    fn wind_in_place(&self, wind: &WindParams) -> crate::Result<Result<(), String>> {
        let strands = self.frame.strands();
        let reach = strands.reach_with_wind(wind)?;
        Ok(if reach == strands.buffers().reach {
            Ok(())
        } else {
            Err("hair.wind (it changes how far the groom can swing, which sizes the shadows and the level of detail)".into())
        })
    }
}
