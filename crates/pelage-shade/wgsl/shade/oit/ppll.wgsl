// Per-pixel linked lists (Yang et al. 2010), shared by the A-buffer and the DBK-buffer.
// A node is 16 bytes: colour and alpha as four halves, depth, and the next node + 1
// (0 ends a list). Nodes come from one pool by an atomic counter; a fragment that
// finds the pool full is counted and dropped, never written out of bounds.
//
// Bindings (@group(3)): heads (one word per pixel of the slice: first node + 1, 0 =
// empty) at 2, the node pool at 3, counters at 4: [0] nodes asked for in this slice,
// [1] fragments dropped on overflow (summed over slices and frames), [2] the most
// nodes any slice asked for, [3] fragments stored (summed).

#import shade/oit/bindings.wgsl

@group(3) @binding(2) var<storage, read_write> heads: array<atomic<u32>>;
@group(3) @binding(3) var<storage, read_write> nodes: array<vec4<u32>>;
@group(3) @binding(4) var<storage, read_write> counters: array<atomic<u32>>;

fn ppll_append(pixel: u32, depth: f32, c: vec4<f32>) {
    let index = atomicAdd(&counters[0], 1u);
    if (index >= tile.capacity) {
        return;
    }
    let next = atomicExchange(&heads[pixel], index + 1u);
    nodes[index] = vec4<u32>(
        pack2x16float(c.rg),
        pack2x16float(c.ba),
        bitcast<u32>(depth),
        next,
    );
}

// Walks the list of `pixel` (at most `capacity` steps, so a corrupt link cannot hang
// the GPU), sorts the `tile.k` nearest fragments and composites them front to back;
// fragments behind those are summed order-independently into one approximate layer
// (as shade/oit/tail.wgsl does) and composited last. Empties the list.
const RESOLVE_K_MAX: u32 = 64u;

fn ppll_resolve(pixel: u32) -> Composite {
    var depths: array<f32, RESOLVE_K_MAX>;
    var colors: array<vec4<f32>, RESOLVE_K_MAX>;
    var n = 0u;
    // Order-independent sums of what does not fit: alpha-weighted colour, alpha,
    // optical depth.
    var rest_color = vec3<f32>(0.0);
    var rest_alpha = 0.0;
    var rest_depth = 0.0;
    var link = atomicExchange(&heads[pixel], 0u);
    var steps = 0u;
    while (link != 0u && link <= tile.capacity && steps < tile.capacity) {
        let node = nodes[link - 1u];
        link = node.w;
        steps += 1u;
        var depth = bitcast<f32>(node.z);
        var color = vec4<f32>(unpack2x16float(node.x), unpack2x16float(node.y));
        if (n < tile.k) {
            n += 1u;
        } else if (depth < depths[n - 1u]) {
            // Evict the farthest kept fragment to the approximate layer.
            let evicted = colors[n - 1u];
            let a = clamp(evicted.a, 0.0, 0.999);
            rest_color += evicted.rgb * a;
            rest_alpha += a;
            rest_depth -= log(1.0 - a);
        } else {
            let a = clamp(color.a, 0.0, 0.999);
            rest_color += color.rgb * a;
            rest_alpha += a;
            rest_depth -= log(1.0 - a);
            continue;
        }
        // Insert into the sorted front list (n already counts the new one).
        var j = n - 1u;
        while (j > 0u && depths[j - 1u] > depth) {
            depths[j] = depths[j - 1u];
            colors[j] = colors[j - 1u];
            j -= 1u;
        }
        depths[j] = depth;
        colors[j] = color;
    }
    var s = composite_start();
    for (var i = 0u; i < n; i += 1u) {
        s = composite_under(s, colors[i]);
    }
    if (rest_alpha > 0.0) {
        s = composite_under(s, vec4<f32>(rest_color / rest_alpha, 1.0 - exp(-rest_depth)));
    }
    return s;
}

// Called by one pixel of each slice's resolve (after the fill pass): moves this
// slice's node count into the totals and resets it for the next slice.
fn ppll_finish_slice() {
    let asked = atomicExchange(&counters[0], 0u);
    atomicAdd(&counters[1], max(asked, tile.capacity) - tile.capacity);
    atomicMax(&counters[2], asked);
    atomicAdd(&counters[3], min(asked, tile.capacity));
}
