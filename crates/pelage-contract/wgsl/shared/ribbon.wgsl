// Which strand vertex, and which side of it, each vertex of a ribbon draw stands for.
// Shared by every pass that draws strands as ribbons (shade/ribbons.wgsl from the
// camera, shadow/hair_light.wgsl from the light). Pure functions, no bindings.
//
// A draw has 6 vertices per segment (two triangles); strand i's vertices start at
// i * (segments + 1) in the strand vertex buffer.

struct RibbonCorner {
    strand: u32,
    // Index into the strand vertex buffer of the vertex this corner sits on, and of
    // its neighbours (clamped at the root and the tip) for the tangent.
    here: u32,
    prev: u32,
    next: u32,
    // -1 or +1: which edge of the ribbon.
    side: f32,
}

const RIBBON_CORNER_END = array<u32, 6>(0u, 0u, 1u, 1u, 0u, 1u);
const RIBBON_CORNER_SIDE = array<f32, 6>(-1.0, 1.0, -1.0, -1.0, 1.0, 1.0);

fn ribbon_corner(vertex_index: u32, segments: u32) -> RibbonCorner {
    let segment = vertex_index / 6u;
    let corner = vertex_index % 6u;
    let strand = segment / segments;
    let k = segment % segments + RIBBON_CORNER_END[corner];
    let base = strand * (segments + 1u);
    var c: RibbonCorner;
    c.strand = strand;
    c.here = base + k;
    c.prev = base + select(k - 1u, 0u, k == 0u);
    c.next = base + min(k + 1u, segments);
    c.side = RIBBON_CORNER_SIDE[corner];
    return c;
}
