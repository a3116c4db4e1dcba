// The test kernel around the WGSL collector search (tests/search.rs, tests/naga_outputs.rs):
// the renderer's lit surface is a sphere of cloud of radius 500 m, κ = 0.05/m, lit by a sun
// toward (0, 0.6, 0.8); viewpoints (position, view, behind_min,
// behind_max, sun_depth: 9 f32 each) in; per viewpoint and group
// the search and the finite-cloud factor out (24 f32). The `.ntt` at bindings 3 and 4.
@group(0) @binding(0) var<uniform> job: vec4<u32>;   // viewpoints, groups, mean cosine bits
@group(0) @binding(1) var<storage, read> viewpoints: array<f32>;
@group(0) @binding(2) var<storage, read_write> out: array<f32>;

const SUN = vec3<f32>(0.0, 0.6, 0.8);
const RADIUS: f32 = 500.0;
const KAPPA: f32 = 0.05;

fn sphere_disc(at: vec3<f32>) -> vec2<f32> {
    let b = at.x * SUN.x + at.y * SUN.y + at.z * SUN.z;
    let c = at.x * at.x + at.y * at.y + at.z * at.z - RADIUS * RADIUS;
    return vec2<f32>(b * b - c, b);
}

fn nephele_surface_filtered(at: vec3<f32>, sigma: f32) -> NepheleLitSample {
    let db = sphere_disc(at);
    if !(db.x > 0.0) {
        return NepheleLitSample(vec3<f32>(0.0), vec3<f32>(0.0), 0.0, 0.0, 0u);
    }
    let h = sqrt(db.x);
    let entry = vec3<f32>(at.x + (h - db.y) * SUN.x, at.y + (h - db.y) * SUN.y,
        at.z + (h - db.y) * SUN.z);
    return NepheleLitSample(entry, entry / RADIUS, 2.0 * h, KAPPA * (2.0 * h), 1u);
}

fn nephele_surface_lateral(at: vec3<f32>, sigma: f32) -> NepheleLateralSample {
    let db = sphere_disc(at);
    if !(db.x > 0.0) {
        return NepheleLateralSample(0.0, 0.0, 0u);
    }
    let rho2 = at.x * at.x + at.y * at.y + at.z * at.z - db.y * db.y;
    return NepheleLateralSample(1.0, RADIUS - sqrt(max(rho2, 0.0)), 1u);
}

fn nephele_surface_initial_scale() -> f32 {
    return RADIUS;
}

fn nephele_surface_sun_depth(at: vec3<f32>) -> f32 {
    let db = sphere_disc(at);
    var d = 0.0;
    if db.x > 0.0 {
        d = sqrt(db.x) - db.y;
    }
    return KAPPA * max(d, 0.0);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= job.x * job.y {
        return;
    }
    let k = i / job.y;
    let g = i % job.y;
    let b = 9u * k;
    let v = NepheleViewpoint(vec3<f32>(viewpoints[b], viewpoints[b + 1u], viewpoints[b + 2u]),
        vec3<f32>(viewpoints[b + 3u], viewpoints[b + 4u], viewpoints[b + 5u]), viewpoints[b + 6u],
        viewpoints[b + 7u], viewpoints[b + 8u]);
    let c = nephele_find_collector(g, v, SUN, NepheleSearchOptions(8u, 0.1, 1u, 1u, 1u,
        bitcast<f32>(job.z)));
    var kept = NepheleKept(1.0, NEPHELE_F32_MAX, 1.0);
    if c.found != 0u {
        kept = nephele_finite_cloud(g, c, NepheleFiniteCloud(1u, 0u, 1.0, 0.0, 1u, 0.0,
            bitcast<f32>(job.z)));
    }
    let o = 24u * i;
    out[o] = f32(c.found);
    out[o + 1u] = f32(c.reads);
    out[o + 2u] = f32(c.converged);
    out[o + 3u] = f32(c.clamps);
    out[o + 4u] = c.transport.t;
    out[o + 5u] = c.transport.c_x;
    out[o + 6u] = c.transport.c_z;
    out[o + 7u] = c.transport.sigma;
    out[o + 8u] = c.at.depth;
    out[o + 9u] = c.at.thickness;
    out[o + 10u] = c.at.mu_v;
    out[o + 11u] = c.at.psi_v;
    out[o + 12u] = c.at.mu_l;
    out[o + 13u] = c.centre.x;
    out[o + 14u] = c.centre.y;
    out[o + 15u] = c.centre.z;
    out[o + 16u] = c.sigma;
    out[o + 17u] = c.extinction;
    out[o + 18u] = kept.factor;
    out[o + 19u] = kept.radius;
    out[o + 20u] = kept.coverage;
    out[o + 21u] = nephele_view_weight(c.at, 0.5);
}
