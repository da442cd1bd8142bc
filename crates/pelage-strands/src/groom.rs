//! Stage 1 for a groom read from a file: the strands of a `.hair` or `.tfx` file, bent
//! by the wind every frame (`wgsl/strands/groom.wgsl`).

use glam::{Vec2, Vec3};
use pelage_gpu::{Gpu, storage_buffer, wgpu};
use pelage_scene::{CameraMatrices, HairParams, HairType, ParamError, Resampled};

use crate::grow::{StrandPass, StrandStage};
use crate::lod::{bend_error, bend_per_segment, fewest_segments};
use crate::{LodLevel, StrandRoot, hash_to_unit, pcg_hash};

/// Stage 1 for a groom file ([`Resampled`], from `pelage_scene::GroomSource::load` or
/// `Groom::resample`): the roots stay where the file puts them, every segment keeps its
/// rest length and direction relative to the one before it, and the wind of
/// `HairParams::wind` turns each segment by `growth.force_weight · F` the way it bends
/// grown fur, so the groom's own curls ride along. With no wind (no force at all) the
/// file's strands come out exactly: every vertex is the resampled rest point.
///
/// Of [`HairParams`] it uses the wind, the level of detail, `roots.seed` (the strand
/// order and per-strand jitter), and of `growth` the width (for strands the file gives
/// no width), `tip_width`, colour (for a groom without per-strand colours,
/// [`Resampled::colors`]; a USD file's `displayColor`), `color_jitter`, opacity and
/// `force_weight`. Gravity is
/// not applied: a groom's rest shape already hangs under it. [`StrandStage::params`]
/// returns the parameters the groom amounts to (strand count, segments, longest strand,
/// mean width), which the later stages size themselves by.
///
/// The strands are shuffled on upload (from `roots.seed`), so that the level of detail's
/// prefix of the buffer is a random subset of the groom;
/// [`GroomStrands::source_strands`] maps each back to the file.
///
/// ```no_run
/// # fn demo(gpu: &pelage_gpu::Gpu) -> Result<(), Box<dyn std::error::Error>> {
/// use pelage_scene::{GroomSource, HairParams};
/// use pelage_strands::{GroomStrands, StrandStage};
/// let groom = GroomSource { fit: Some(1.8), ..GroomSource::new("long_hair.hair") }.load()?;
/// let mut strands = GroomStrands::new(gpu, &groom, &HairParams::default())?;
/// let frame = strands.prepare(&gpu.queue, 0.5)?;
/// let mut encoder = gpu.device.create_command_encoder(&Default::default());
/// strands.encode(&mut encoder, &frame, None)?;
/// gpu.queue.submit([encoder.finish()]);
/// # Ok(()) }
/// ```
#[derive(Debug)]
pub struct GroomStrands {
    shape: GroomShape,
    pass: StrandPass,
    /// The rest roots the pass reads (rewritten by [`StrandStage::set_color`]).
    rest_roots: wgpu::Buffer,
}

/// A groom's strands as [`GroomStrands`] holds them on the CPU: shuffled from
/// `roots.seed`, coloured and sized. [`SimulateStrands::groom`](crate::SimulateStrands::groom)
/// and simulated [`GuideStrands`](crate::GuideStrands) start from this, without the
/// groom pass's buffers.
#[derive(Debug)]
pub(crate) struct GroomShape {
    /// What the groom amounts to ([`GroomStrands::params_for`]).
    pub(crate) params: HairParams,
    pub(crate) roots: Vec<StrandRoot>,
    /// Rest points in buffer order, `segments + 1` per strand.
    pub(crate) rest: Vec<Vec3>,
    /// The groom's index of every strand in the buffer.
    pub(crate) source_strands: Vec<u32>,
    /// `chord_error[k]`: the farthest any rest point is from the chord that skips it when
    /// every `k`-th vertex is kept, world units (0 where `k` does not divide the segments).
    pub(crate) chord_error: Vec<f32>,
    /// The longest rest segment, world units.
    pub(crate) longest_segment: f32,
    /// The groom's colour of every strand in buffer order, if it has colours.
    pub(crate) file_colors: Option<Vec<Vec3>>,
}

impl GroomShape {
    /// Shuffles, colours and sizes the strands of `groom` drawn with `hair`.
    ///
    /// Errors: as [`GroomStrands::new`] (bad parameters, a groom whose arrays do not
    /// agree, one the device cannot bind).
    pub(crate) fn new(gpu: &Gpu, groom: &Resampled, hair: &HairParams) -> crate::Result<Self> {
        let params = GroomStrands::params_for(groom, hair)?;
        // Refuse a groom the device cannot hold before shuffling it.
        StrandPass::vertex_bytes(gpu, &params)?;
        let per_strand = groom.segments as usize + 1;
        let order = shuffled(groom.strands, hair.roots.seed);
        let seed_hash = pcg_hash(hair.roots.seed);
        let g = &hair.growth;
        let mut rest = Vec::with_capacity(groom.points.len());
        let mut roots = Vec::with_capacity(order.len());
        for (index, &source) in order.iter().enumerate() {
            let first = source as usize * per_strand;
            let points = &groom.points[first..first + per_strand];
            rest.extend_from_slice(points);
            let h0 = pcg_hash(index as u32 ^ seed_hash);
            let mut h = h0;
            let mut next = || {
                h = pcg_hash(h);
                hash_to_unit(h)
            };
            let phase = next();
            let brightness = 1.0 + g.color_jitter * (2.0 * next() - 1.0);
            let color = file_color(groom, source).unwrap_or(g.color);
            roots.push(StrandRoot {
                triangle: 0,
                seed: h0,
                bary: Vec2::ZERO,
                length: polyline_length(points),
                width: root_width(groom, first).unwrap_or(g.width),
                phase,
                tilt: 0.0,
                azimuth: 0.0,
                color: color * brightness,
                region: 0,
            });
        }
        let file_colors = groom.colors.as_ref().map(|_| {
            order
                .iter()
                .map(|&i| file_color(groom, i).unwrap_or(g.color))
                .collect()
        });
        let source_strands = order
            .iter()
            .map(|&i| groom.source_strands.get(i as usize).copied().unwrap_or(i))
            .collect();
        let chord_error = chord_errors(&rest, groom.segments);
        let longest_segment = rest
            .chunks(per_strand)
            .flat_map(|s| s.windows(2).map(|w| w[0].distance(w[1])))
            .fold(0.0f32, f32::max);
        Ok(Self {
            params,
            roots,
            rest,
            source_strands,
            chord_error,
            longest_segment,
            file_colors,
        })
    }
}

impl GroomStrands {
    /// Shuffles the groom's strands, uploads their rest shape and builds the pipeline.
    ///
    /// Errors: bad parameters (naming them), a [`Resampled`] whose arrays do not agree
    /// or hold a non-finite point (its fields are public), and a groom the device
    /// cannot bind.
    pub fn new(gpu: &Gpu, groom: &Resampled, hair: &HairParams) -> crate::Result<Self> {
        Self::labelled(gpu, groom, hair, "strands: groom")
    }

    /// [`GroomStrands::new`] with the pass timed as `label` (the guides of
    /// [`GuideStrands`](crate::GuideStrands) are bent by this pass).
    pub(crate) fn labelled(
        gpu: &Gpu,
        groom: &Resampled,
        hair: &HairParams,
        label: &'static str,
    ) -> crate::Result<Self> {
        let shape = GroomShape::new(gpu, groom, hair)?;
        let storage = wgpu::BufferUsages::STORAGE;
        let rest_gpu: Vec<glam::Vec4> = shape.rest.iter().map(|p| p.extend(0.0)).collect();
        let rest_buffer = storage_buffer(gpu, "pelage groom rest points", &rest_gpu, storage)?;
        let rest_roots = storage_buffer(gpu, "pelage groom rest roots", &shape.roots, storage)?;
        pelage_gpu::audit::constant(&[&rest_buffer, &rest_roots]);
        let pass = StrandPass::new(
            gpu,
            label,
            "strands/groom.wgsl",
            &shape.params,
            Self::reach_of(groom, hair)?,
            &shape.roots,
            &[&rest_buffer, &rest_roots],
        )?;
        Ok(Self {
            shape,
            pass,
            rest_roots,
        })
    }

    /// The parameters `groom` drawn with `hair` amounts to (what
    /// [`StrandStage::params`] returns): `roots.count` its strand count,
    /// `growth.segments` its segments, `growth.length` its longest strand,
    /// `growth.width` its mean root width, no gravity, no shape or jitter of growth.
    ///
    /// Errors: bad parameters of `hair` (its roots aside), and a groom whose arrays do
    /// not agree or hold a non-finite point or width.
    pub fn params_for(groom: &Resampled, hair: &HairParams) -> crate::Result<HairParams> {
        hair.growth.validate()?;
        hair.wind.validate()?;
        hair.lod.validate()?;
        check_groom(groom)?;
        let per_strand = groom.segments as usize + 1;
        let mut longest = 0.0f32;
        let mut width_sum = 0.0f64;
        for (strand, points) in groom.points.chunks(per_strand).enumerate() {
            longest = longest.max(polyline_length(points));
            let width = root_width(groom, strand * per_strand).unwrap_or(hair.growth.width);
            width_sum += f64::from(width);
        }
        let mut params = hair.clone();
        params.roots.count = groom.strands;
        params.roots.density = None;
        params.roots.length_scale = None;
        let g = &mut params.growth;
        g.segments = groom.segments;
        g.length = longest;
        g.length_jitter = 0.0;
        g.direction_jitter = 0.0;
        g.width = (width_sum / f64::from(groom.strands.max(1))) as f32;
        g.gravity = Vec3::ZERO;
        g.hair_type = HairType::Straight;
        params.growth.validate()?;
        Ok(params)
    }

    /// A world box holding every point the strands of `groom` can reach when drawn with
    /// `hair`: the rest bounds grown by how far the strongest wind can turn the longest
    /// strand (at most its length) and by the width.
    pub fn reach_of(groom: &Resampled, hair: &HairParams) -> crate::Result<(Vec3, Vec3)> {
        let params = Self::params_for(groom, hair)?;
        Ok(reach_around(groom.bounds(), &params))
    }

    /// The rest points of every strand in buffer order, `segments + 1` per strand (input
    /// of the CPU mirror `pelage_reference::strands::deform_groom`).
    pub fn rest_points(&self) -> &[Vec3] {
        &self.shape.rest
    }

    /// The groom's own colour of every strand in buffer order (`displayColor`, a .hair
    /// file's colours), before the per-strand brightness jitter; `None` without colours.
    pub fn file_colors(&self) -> Option<&[Vec3]> {
        self.shape.file_colors.as_deref()
    }

    /// The groom's index of every strand in the buffer (the file's strand, counting the
    /// degenerate ones `Resampled` skipped).
    pub fn source_strands(&self) -> &[u32] {
        &self.shape.source_strands
    }

    /// The strands' shape, roots and colours on the CPU.
    pub(crate) fn shape(&self) -> &GroomShape {
        &self.shape
    }
}

/// [`GroomStrands::reach_of`] for rest points inside `(lo, hi)` and the parameters the
/// groom amounts to.
fn reach_around((lo, hi): (Vec3, Vec3), params: &HairParams) -> (Vec3, Vec3) {
    // Segment j turns by at most j·turn from its rest direction, and a unit vector
    // turned by θ moves by 2 sin(θ/2) <= min(θ, 2).
    let turn = bend_per_segment(&params.growth, &params.wind);
    let segments = params.growth.segments;
    let seg = params.growth.length / segments as f32;
    let swing: f32 = (1..=segments)
        .map(|j| seg * (j as f32 * turn).min(2.0))
        .sum();
    let pad = Vec3::splat(swing.min(params.growth.length) + params.growth.width);
    (lo - pad, hi + pad)
}

/// The hash draw a groom strand's brightness comes from (after its phase; see
/// [`GroomStrands::new`]).
pub(crate) const GROOM_BRIGHTNESS_DRAW: u32 = 2;

impl StrandStage for GroomStrands {
    fn pass(&self) -> &StrandPass {
        &self.pass
    }

    fn pass_mut(&mut self) -> &mut StrandPass {
        &mut self.pass
    }

    fn roots(&self) -> &[StrandRoot] {
        &self.shape.roots
    }

    fn reach_with_wind(&self, wind: &pelage_scene::WindParams) -> crate::Result<(Vec3, Vec3)> {
        wind.validate()?;
        let rest = &self.shape.rest;
        let first = rest.first().copied().unwrap_or(Vec3::ZERO);
        let bounds = (rest.iter()).fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        let mut params = self.params().clone();
        params.wind = wind.clone();
        Ok(reach_around(bounds, &params))
    }

    fn set_color(
        &mut self,
        queue: &wgpu::Queue,
        color: Vec3,
        color_jitter: f32,
    ) -> crate::Result<()> {
        crate::grow::recolor(
            &mut self.pass,
            &mut self.shape.roots,
            &self.rest_roots,
            GROOM_BRIGHTNESS_DRAW,
            queue,
            (color, color_jitter),
        )?;
        // A groom's own colours stay; only their jitter changes.
        let drawn = StrandStage::buffers(self).roots.clone();
        keep_file_colors(
            &mut self.shape.roots,
            (&self.rest_roots, &drawn),
            self.shape.file_colors.as_deref(),
            (GROOM_BRIGHTNESS_DRAW, color_jitter),
            queue,
        )
    }

    /// Segment reduction measured on the rest shape: the farthest rest point from the
    /// chord that skips it, plus the bend the wind can add (the bound grown fur uses).
    fn level_for_view(
        &self,
        bounds: (Vec3, Vec3),
        camera: &CameraMatrices,
        width: u32,
        height: u32,
    ) -> LodLevel {
        let params = self.params();
        let full = params.growth.segments;
        let turn = bend_per_segment(&params.growth, &params.wind);
        let max_error = params.lod.segment_error_pixels;
        LodLevel::for_view_with(params, bounds, camera, width, height, |pixels_per_unit| {
            fewest_segments(full, max_error, pixels_per_unit, |k| {
                let rest = (self.shape.chord_error)
                    .get(k as usize)
                    .copied()
                    .unwrap_or(f32::MAX);
                rest + bend_error(k, self.shape.longest_segment, turn)
            })
        })
    }
}

/// Refuses a [`Resampled`] whose arrays do not agree or hold non-finite values.
fn check_groom(groom: &Resampled) -> Result<(), ParamError> {
    if groom.strands == 0 {
        return Err(ParamError::new(
            "groom.strands",
            groom.strands,
            "must be at least 1: the groom has no strand to draw",
        ));
    }
    if groom.segments == 0 || groom.segments > pelage_scene::MAX_SEGMENTS {
        return Err(ParamError::new(
            "groom.segments",
            groom.segments,
            &format!("must be in 1..={}", pelage_scene::MAX_SEGMENTS),
        ));
    }
    let expected = u64::from(groom.strands) * u64::from(groom.segments + 1);
    if groom.points.len() as u64 != expected {
        return Err(ParamError::new(
            "groom.points",
            groom.points.len(),
            &format!(
                "must hold strands x (segments + 1) = {expected} points; build it with Groom::resample"
            ),
        ));
    }
    if let Some(widths) = &groom.widths {
        if widths.len() != groom.points.len() {
            return Err(ParamError::new(
                "groom.widths",
                widths.len(),
                &format!("must hold one width per point ({})", groom.points.len()),
            ));
        }
        if let Some(w) = widths.iter().find(|w| !(w.is_finite() && **w >= 0.0)) {
            return Err(ParamError::new(
                "groom.widths",
                w,
                "every width must be finite and >= 0",
            ));
        }
    }
    if let Some(colors) = &groom.colors {
        if colors.len() != groom.strands as usize {
            return Err(ParamError::new(
                "groom.colors",
                colors.len(),
                &format!("must hold one colour per strand ({})", groom.strands),
            ));
        }
        if let Some(c) = colors
            .iter()
            .find(|c| !(c.is_finite() && c.min_element() >= 0.0))
        {
            return Err(ParamError::new(
                "groom.colors",
                c,
                "every colour must be finite and >= 0",
            ));
        }
    }
    if let Some(p) = groom
        .points
        .iter()
        .find(|p| !p.is_finite() || p.abs().max_element() > pelage_scene::MAX_EXTENT)
    {
        return Err(ParamError::new(
            "groom.points",
            p,
            &format!(
                "every point must be finite and at most {:e} in magnitude (scale the groom down)",
                pelage_scene::MAX_EXTENT
            ),
        ));
    }
    Ok(())
}

/// After [`crate::grow::recolor`]: strands with colours of their own (`colors`, one per
/// root; none: nothing to do) keep them, times their brightness from the `draw`-th hash
/// draw with `jitter`; rewrites the rest and drawn roots (`rest_roots`, `drawn_roots`).
pub(crate) fn keep_file_colors(
    roots: &mut [StrandRoot],
    (rest_roots, drawn_roots): (&wgpu::Buffer, &wgpu::Buffer),
    colors: Option<&[Vec3]>,
    (draw, jitter): (u32, f32),
    queue: &wgpu::Queue,
) -> crate::Result<()> {
    let Some(colors) = colors else {
        return Ok(());
    };
    for (root, &base) in roots.iter_mut().zip(colors) {
        root.color = base * crate::strand_brightness(root.seed, draw, jitter);
    }
    pelage_gpu::write_storage(queue, "pelage strand rest roots", rest_roots, &*roots)?;
    pelage_gpu::write_storage(queue, "pelage strand roots", drawn_roots, &*roots)?;
    Ok(())
}

/// The groom's colour of its strand `strand`, when it has colours.
fn file_color(groom: &Resampled, strand: u32) -> Option<Vec3> {
    groom
        .colors
        .as_ref()
        .and_then(|c| c.get(strand as usize))
        .copied()
}

/// The file's width at point `first` (a strand's root), when it has a positive one.
fn root_width(groom: &Resampled, first: usize) -> Option<f32> {
    groom
        .widths
        .as_ref()
        .and_then(|w| w.get(first))
        .copied()
        .filter(|w| *w > 0.0)
}

/// Length of a polyline.
fn polyline_length(points: &[Vec3]) -> f32 {
    points.windows(2).map(|w| w[0].distance(w[1])).sum()
}

/// `0..count` in a random order fixed by `seed` (Fisher-Yates on `pcg_hash`).
fn shuffled(count: u32, seed: u32) -> Vec<u32> {
    let mut order: Vec<u32> = (0..count).collect();
    let mut h = pcg_hash(seed ^ 0x2545_f491);
    for i in (1..order.len()).rev() {
        h = pcg_hash(h);
        let j = ((u64::from(h) * (i as u64 + 1)) >> 32) as usize;
        order.swap(i, j);
    }
    order
}

/// For every step `k` (index `k`, `0..=segments`) that divides `segments`, the farthest
/// any point of `rest` (`segments + 1` per strand) is from the chord between the kept
/// vertices around it; 0 elsewhere and for `k` = 1.
fn chord_errors(rest: &[Vec3], segments: u32) -> Vec<f32> {
    let per_strand = segments as usize + 1;
    let mut out = vec![0.0f32; per_strand];
    for (k, slot) in out.iter_mut().enumerate().skip(2) {
        if !segments.is_multiple_of(k as u32) {
            continue;
        }
        let mut worst = 0.0f32;
        for strand in rest.chunks(per_strand) {
            for span in strand.windows(k + 1).step_by(k) {
                let (a, b) = (span[0], span[k]);
                for &p in &span[1..k] {
                    worst = worst.max(distance_to_segment(p, a, b));
                }
            }
        }
        *slot = worst;
    }
    out
}

/// Distance from `p` to the segment `a`-`b`.
fn distance_to_segment(p: Vec3, a: Vec3, b: Vec3) -> f32 {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + ab * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shuffle_is_a_permutation_and_depends_on_the_seed() {
        let a = shuffled(1000, 1);
        let mut sorted = a.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..1000).collect::<Vec<_>>());
        assert_ne!(a, shuffled(1000, 2));
        assert_ne!(a, sorted);
        assert_eq!(shuffled(1, 7), vec![0]);
        assert!(shuffled(0, 7).is_empty());
    }

    #[test]
    fn chord_error_of_a_straight_strand_is_zero_and_of_a_bend_is_its_sagitta() {
        // 4 segments along x, then the same strand with its middle vertex lifted by 0.1.
        let straight: Vec<Vec3> = (0..5).map(|i| Vec3::X * i as f32).collect();
        let e = chord_errors(&straight, 4);
        assert!(e.iter().all(|&v| v.abs() < 1e-6), "{e:?}");
        let mut bent = straight.clone();
        bent[2].y = 0.1;
        let e = chord_errors(&bent, 4);
        assert_eq!(e[3], 0.0, "3 does not divide 4");
        assert!((e[4] - 0.1).abs() < 1e-6, "{e:?}");
        // Keeping every 2nd vertex keeps the lifted one; (1, 0, 0) is then 0.1 / |(2, 0.1)|
        // from the chord (0, 0) - (2, 0.1).
        let expected = 0.1 / Vec2::new(2.0, 0.1).length();
        assert!((e[2] - expected).abs() < 1e-6, "{e:?}");
    }
}
