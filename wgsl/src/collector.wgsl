// T, the collector c = (c_x, c_z) and its spread σ (mfp) of one order group at a slab point:
// nephele-runtime's `TransportTables::evaluate`. The collector form (docs/compress.md) reads,
// with the same cell and the group's fitted depths as T,
//
//   ln σ   = Σ_i h_i(Θ)(α_i + α′_i x) + Σ_{k=0}^{K} (s_V s_L)^k cos kψ Σ_j [a_kj + b_kj] P_j(x)
//   c_z/σ̂ = Σ_i h_i(Θ)(ζ_i + ζ′_i x) + s_L Σ_j [·] P_j(x) + Σ_{k=1}^{K} cos kψ Σ_j [·] P_j(x)
//           + (ℓ/σ̂) [Σ_i h_i(Θ)(η_i + η′_i x) + s_L Σ_j [·] P_j(x)]
//   c_x/σ̂ = sin ψ Σ_i h_i(Θ)(ξ_i + ξ′_i x) + Σ_{k=1}^{K} sin kψ Σ_j [·] P_j(x)
//
// x = 2u − 1 with u held within the fitted depths, ℓ = s_L λ (1 − e^{−d/(μ_L λ)}), λ = 8 mfp
// (μ_L held ≥ 0.05); c_z's ℓ/σ̂ terms are summed apart and divided by σ after. Needs ntt.wgsl,
// order1.wgsl and transport.wgsl before it.

// One group at a point: T (sr⁻¹), c_x, c_z and σ (mfp); c and σ are 0 where T is.
struct NepheleTransport {
    t: f32,
    c_x: f32,
    c_z: f32,
    sigma: f32,
}

// The statistics: 0 ln σ, 1 c_z/σ̂, 2 c_x/σ̂. A block is the Θ table (kind 0) or the depth
// polynomials on the cosine nodes (kind 1), times a value.
fn nc_block(stat: u32, b: u32, c: NtCell) -> vec3<f32> {
    // (kind, value, exists)
    let x = nephele_ntt_index;
    let k_max = min(x.c_harmonics, 4u);
    let s_l = sqrt(clamp(1.0 - c.at.mu_l * c.at.mu_l, 0.0, 1.0));
    let s_v = sqrt(clamp(1.0 - c.at.mu_v * c.at.mu_v, 0.0, 1.0));
    let psi = c.at.psi_v;
    if stat == 0u {
        if b == 0u {
            return vec3<f32>(0.0, 1.0, 1.0);
        }
        if b <= k_max + 1u {
            let k = b - 1u;
            var s_k = 1.0;
            for (var i = 0u; i < k; i++) {
                s_k = s_k * s_v * s_l;
            }
            return vec3<f32>(1.0, s_k * nephele_sin_cos(f32(k) * psi).y, 1.0);
        }
        return vec3<f32>(0.0);
    }
    if stat == 1u {
        let mu_l = select(0.05, c.at.mu_l, c.at.mu_l > 0.05);
        let reach = s_l * 8.0 * -nephele_exp_m1(-c.at.depth / (mu_l * 8.0)) * 1.0;
        if b == 0u {
            return vec3<f32>(0.0, 1.0, 1.0);
        }
        if b == 1u {
            return vec3<f32>(1.0, s_l, 1.0);
        }
        if b <= k_max + 1u {
            return vec3<f32>(1.0, nephele_sin_cos(f32(b - 1u) * psi).y, 1.0);
        }
        if b == k_max + 2u {
            return vec3<f32>(0.0, reach, 1.0);
        }
        if b == k_max + 3u {
            return vec3<f32>(1.0, reach * s_l, 1.0);
        }
        return vec3<f32>(0.0);
    }
    if b == 0u {
        return vec3<f32>(0.0, nephele_sin_cos(psi).x, 1.0);
    }
    if b <= k_max {
        return vec3<f32>(1.0, nephele_sin_cos(f32(b) * psi).x, 1.0);
    }
    return vec3<f32>(0.0);
}

// Adds the features of statistic `stat` at `c` (σ̂ = 1) to the running sums.
fn nc_features(stat: u32, c: NtCell) {
    let x = nephele_ntt_index;
    var col = 0u;
    for (var b = 0u; b < 12u; b++) {
        let block = nc_block(stat, b, c);
        if block.z == 0.0 {
            break;
        }
        if block.x == 0.0 {
            nt_theta_hats(c, col, block.y, x.c_theta_nodes, x.c_theta_hats);
            col += 2u * x.c_theta_nodes;
        } else {
            for (var j = 0u; j < min(x.c_legendre, NT_MAX_LEGENDRE); j++) {
                nt_on_nodes(c, col, block.y, j);
                col += x.n_v + x.n_l;
            }
        }
    }
}

// One part of a statistic for group g at its depth: Σ_j d_j P_j(x).
fn nc_part(g: u32, stat: u32, cols: vec2<u32>, r: NtT, p_x: array<f32, 16>) -> f32 {
    let x = nephele_ntt_index;
    var beta = x.sigma_beta;
    var group_stride = x.sigma_group_stride;
    if stat == 1u {
        beta = x.cz_beta;
        group_stride = x.cz_group_stride;
    } else if stat == 2u {
        beta = x.cx_beta;
        group_stride = x.cx_group_stride;
    }
    nt_begin(g, NtPass(beta, x.c_param_stride, group_stride, x.c_q, cols.x, cols.y));
    nc_features(stat, r.cell);
    let depth = min(x.c_depth_terms, 8u);
    let d = nt_depth_sums(r.s, depth);
    var sum = 0.0;
    for (var j = 0u; j < depth; j++) {
        sum += d[j] * p_x[j];
    }
    return sum;
}

// T, c and σ of group g at `at` (the runtime's `evaluate`); past the thickest slab T and σ
// continued by diffusion theory, c held.
fn evaluate(g: u32, at: SlabPoint) -> NepheleTransport {
    let c = nt_continued(at);
    var out = nc_evaluate(g, c.at);
    out.t *= nt_diffuse_scale(g, c);
    out.sigma *= select(c.spread, c.spread_diffuse, g + 1u == nephele_ntt_index.groups);
    return out;
}

// T, c and σ of group g at a point within the grid's thicknesses.
fn nc_evaluate(g: u32, at: SlabPoint) -> NepheleTransport {
    let x = nephele_ntt_index;
    let r = nt_transport(g, at);
    var out = NepheleTransport(r.t, 0.0, 0.0, 0.0);
    if !(r.t > 0.0) || x.has_collector == 0u {
        return out;
    }
    // c and σ are held within the fitted depths.
    let u = nt_held(r.range, r.cell.u);
    let p_x = nt_legendre(2.0 * u - 1.0, min(x.c_depth_terms, 8u));
    let all = vec2<u32>(0u, 0xffffffffu);
    let sigma = nephele_exp(nc_part(g, 0u, all, r, p_x));
    let cz_main = nc_part(g, 1u, vec2<u32>(0u, x.cz_reach), r, p_x);
    let cz_reach = nc_part(g, 1u, vec2<u32>(x.cz_reach, 0xffffffffu), r, p_x);
    let cx = nc_part(g, 2u, all, r, p_x);
    out.c_x = sigma * cx;
    out.c_z = sigma * (cz_main + cz_reach / sigma);
    out.sigma = sigma;
    return out;
}
