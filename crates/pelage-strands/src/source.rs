//! Where a scene's strands come from: the one place a scene's groom, guides and dynamics
//! choose stage 1's method, and the world box the hair of that method can reach.

use glam::Vec3;
use pelage_scene::{Camera, DynamicsParams, GuideParams, Resampled, Scene};

use crate::{GroomStrands, GrowStrands, GuideStrands, LodLevel};

/// Stage 1's method for a scene: which of the strand stages draws its hair.
#[derive(Clone, Copy, Debug)]
pub enum StrandSource<'a> {
    /// Fur grown from the mesh ([`GrowStrands`]).
    Grown,
    /// A groom's own strands bent by the wind ([`GroomStrands`]).
    Groom(&'a Resampled),
    /// Render strands interpolated from a groom's strands as guides ([`GuideStrands`]).
    Guides(&'a Resampled, &'a GuideParams),
    /// The guides simulated, the render strands interpolated from them
    /// ([`GuideStrands::simulated`]).
    SimulatedGuides(&'a Resampled, &'a GuideParams, &'a DynamicsParams),
    /// Grown fur (`None`) or a groom simulated ([`crate::SimulateStrands`]).
    Simulated(Option<&'a Resampled>, &'a DynamicsParams),
}

impl<'a> StrandSource<'a> {
    /// The source `scene` asks for (its `groom`, `guides` and `dynamics`).
    pub fn of(scene: &'a Scene) -> Self {
        match (&scene.groom, &scene.guides, &scene.dynamics) {
            (Some(groom), Some(guides), None) => Self::Guides(groom, guides),
            (Some(groom), Some(guides), Some(d)) => Self::SimulatedGuides(groom, guides, d),
            (Some(groom), None, None) => Self::Groom(groom),
            (groom, _, Some(d)) => Self::Simulated(groom.as_ref(), d),
            (None, _, None) => Self::Grown,
        }
    }
}

/// A world box holding `scene`'s mesh and everything that can grow on it: the mesh's
/// bounds and [`GrowStrands::reach_of`]; with a groom, the mesh's bounds (none for an
/// empty mesh) and the groom's reach ([`GroomStrands::reach_of`]; the rest bounds alone
/// when its parameters are bad, which building the frame then refuses).
///
/// A simulated groom (or simulated guides) reaches its longest strand (and width) around
/// its rest bounds; with a mesh motion the box is the sphere around the pivot holding it,
/// and with a skin rig the box holding every pose of its moving joint.
pub fn scene_reach(scene: &Scene) -> (Vec3, Vec3) {
    let (lo, hi) = scene.mesh.bounds();
    // A simulated groom: its longest strand (and width) around its rest bounds.
    let simulated = |groom: &Resampled| {
        let pad = GroomStrands::params_for(groom, &scene.hair)
            .map_or(0.0, |p| p.growth.length + p.growth.width);
        let (a, b) = groom.bounds();
        (a - Vec3::splat(pad), b + Vec3::splat(pad))
    };
    let (glo, ghi) = match StrandSource::of(scene) {
        StrandSource::Guides(groom, guides) => {
            GuideStrands::reach_of(groom, (lo, hi), &scene.hair, guides)
                .unwrap_or_else(|_| groom.bounds())
        }
        StrandSource::SimulatedGuides(groom, guides, _) => {
            GuideStrands::reach_around(simulated(groom), (lo, hi), groom, &scene.hair, guides)
                .unwrap_or_else(|_| groom.bounds())
        }
        StrandSource::Groom(groom) => {
            GroomStrands::reach_of(groom, &scene.hair).unwrap_or_else(|_| groom.bounds())
        }
        StrandSource::Simulated(Some(groom), _) => simulated(groom),
        StrandSource::Simulated(None, _) | StrandSource::Grown => {
            GrowStrands::reach_of(&scene.mesh, &scene.hair)
        }
    };
    // A groom-only scene: the hair's reach alone.
    if scene.groom.is_some() && scene.mesh.indices.is_empty() {
        return (glo, ghi);
    }
    let reach = (lo.min(glo), hi.max(ghi));
    let reach = scene.skin.as_ref().map_or(reach, |s| s.reach(reach));
    scene.motion.as_ref().map_or(reach, |m| m.reach(reach))
}

/// `scene` with its shadow grid or maps sized to the hair's size on screen from `camera`
/// on a `width` x `height` target (`ShadowParams::sized_for`): nothing finer than the
/// picture can show. Unchanged when the hair's box reaches behind the camera.
pub fn sized_for_view(scene: &Scene, camera: &Camera, width: u32, height: u32) -> Scene {
    let matrices = camera.matrices(width, height);
    let level = LodLevel::for_view(&scene.hair, scene_reach(scene), &matrices, width, height);
    let mut out = scene.clone();
    if level.extent_pixels.is_finite() {
        out.shadow = scene.shadow.sized_for(level.extent_pixels);
    }
    out
}
