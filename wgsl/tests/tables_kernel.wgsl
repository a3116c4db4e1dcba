// The test kernel around the WGSL tables (tests/tables.rs, tests/naga_outputs.rs): points
// (thickness, μ_L, depth, μ_V, ψ_V) in; per point order 1 and (T, c_x, c_z, σ) of groups
// 0 … G − 1 out (4 G + 1 values); the `.ntt` at bindings 3 (words) and 4 (index):
// nephele_wgsl::tables(0, 3).
@group(0) @binding(0) var<uniform> job: vec4<u32>;   // points, groups
@group(0) @binding(1) var<storage, read> points: array<f32>;
@group(0) @binding(2) var<storage, read_write> out: array<f32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= job.x {
        return;
    }
    let b = 5u * i;
    let at = nephele_slab_point(points[b], points[b + 1u], points[b + 2u], points[b + 3u],
        points[b + 4u]);
    let stride = 4u * job.y + 1u;
    out[stride * i] = nephele_order1(at);
    let all = nephele_evaluate_all(at);
    for (var g = 0u; g < job.y; g++) {
        let e = all[g];
        let o = stride * i + 1u + 4u * g;
        out[o] = e.t;
        out[o + 1u] = e.c_x;
        out[o + 2u] = e.c_z;
        out[o + 3u] = e.sigma;
    }
}
