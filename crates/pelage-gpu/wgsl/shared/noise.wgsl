// Integer hashing and coherent value noise, shared by every stage.
// Reads nothing, writes nothing: pure functions. Mirrored bit for bit on the CPU
// in pelage-reference (noise.rs); change both together.

// PCG hash (Jarzynski and Olano 2020): one u32 in, one well-mixed u32 out.
fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// A float in [0, 1) from the top 24 bits of a hash (exact in f32).
fn hash_to_unit(h: u32) -> f32 {
    return f32(h >> 8u) * (1.0 / 16777216.0);
}

// Hash of an integer lattice point and a seed.
fn hash_cell(c: vec3<i32>, seed: u32) -> u32 {
    return pcg_hash(bitcast<u32>(c.x) ^ pcg_hash(bitcast<u32>(c.y) ^ pcg_hash(bitcast<u32>(c.z) ^ seed)));
}

// Quintic fade: C2-continuous interpolation weight.
fn fade(t: f32) -> f32 {
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

// 1-D value noise in [-1, 1], C2 smooth.
fn value_noise_1d(x: f32, seed: u32) -> f32 {
    let i = floor(x);
    let f = x - i;
    let c = i32(i);
    let a = hash_to_unit(pcg_hash(bitcast<u32>(c) ^ seed));
    let b = hash_to_unit(pcg_hash(bitcast<u32>(c + 1) ^ seed));
    return mix(a, b, fade(f)) * 2.0 - 1.0;
}

// 3-D value noise in [-1, 1], C2 smooth (trilinear with quintic weights).
fn value_noise_3d(p: vec3<f32>, seed: u32) -> f32 {
    let i = floor(p);
    let f = p - i;
    let c = vec3<i32>(i);
    let u = vec3<f32>(fade(f.x), fade(f.y), fade(f.z));
    let n000 = hash_to_unit(hash_cell(c, seed));
    let n100 = hash_to_unit(hash_cell(c + vec3<i32>(1, 0, 0), seed));
    let n010 = hash_to_unit(hash_cell(c + vec3<i32>(0, 1, 0), seed));
    let n110 = hash_to_unit(hash_cell(c + vec3<i32>(1, 1, 0), seed));
    let n001 = hash_to_unit(hash_cell(c + vec3<i32>(0, 0, 1), seed));
    let n101 = hash_to_unit(hash_cell(c + vec3<i32>(1, 0, 1), seed));
    let n011 = hash_to_unit(hash_cell(c + vec3<i32>(0, 1, 1), seed));
    let n111 = hash_to_unit(hash_cell(c + vec3<i32>(1, 1, 1), seed));
    let x00 = mix(n000, n100, u.x);
    let x10 = mix(n010, n110, u.x);
    let x01 = mix(n001, n101, u.x);
    let x11 = mix(n011, n111, u.x);
    let y0 = mix(x00, x10, u.y);
    let y1 = mix(x01, x11, u.y);
    return mix(y0, y1, u.z) * 2.0 - 1.0;
}
