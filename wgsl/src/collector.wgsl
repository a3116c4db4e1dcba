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
// polynomials on the cosine nodes (kind 1), times a value; read from the prepared point.
fn nephele_nc_block(stat: u32, b: u32) -> vec3<f32> {
    // (kind, value, exists)
    let k_max = min(nephele_ntt_index.c_harmonics, 4u);
    if stat == 0u {
        if b == 0u {
            return vec3<f32>(0.0, 1.0, 1.0);
        }
        if b <= k_max + 1u {
            let k = b - 1u;
            return vec3<f32>(1.0, nephele_nt_pt.sv_sl_k[k] * nephele_nt_pt.cos_k[k], 1.0);
        }
        return vec3<f32>(0.0);
    }
    if stat == 1u {
        if b == 0u {
            return vec3<f32>(0.0, 1.0, 1.0);
        }
        if b == 1u {
            return vec3<f32>(1.0, nephele_nt_pt.s_l, 1.0);
        }
        if b <= k_max + 1u {
            return vec3<f32>(1.0, nephele_nt_pt.cos_k[b - 1u], 1.0);
        }
        if b == k_max + 2u {
            return vec3<f32>(0.0, nephele_nt_pt.reach, 1.0);
        }
        if b == k_max + 3u {
            return vec3<f32>(1.0, nephele_nt_pt.reach * nephele_nt_pt.s_l, 1.0);
        }
        return vec3<f32>(0.0);
    }
    if b == 0u {
        return vec3<f32>(0.0, nephele_nt_pt.sin_k[1], 1.0);
    }
    if b <= k_max {
        return vec3<f32>(1.0, nephele_nt_pt.sin_k[b], 1.0);
    }
    return vec3<f32>(0.0);
}

// Adds the features of statistic `stat` at the prepared point (σ̂ = 1) to the running sums.
fn nephele_nc_features(stat: u32) {
    let x = nephele_ntt_index;
    let c = nephele_nt_pt.cell;
    var col = 0u;
    for (var b = 0u; b < 12u; b++) {
        let block = nephele_nc_block(stat, b);
        if block.z == 0.0 {
            break;
        }
        if block.x == 0.0 {
            nephele_nt_theta_hats(nephele_nt_pt.c_hat, col, block.y);
            col += 2u * x.c_theta_nodes;
        } else {
            for (var j = 0u; j < min(x.c_legendre, NEPHELE_NT_MAX_LEGENDRE); j++) {
                nephele_nt_on_nodes(c, col, block.y, j);
                col += x.n_v + x.n_l;
            }
        }
    }
}

// One part of a statistic for group g at its depth: Σ_j d_j P_j(x).
fn nephele_nc_part(g: u32, stat: u32, cols: vec2<u32>, r: NepheleNtT, p_x: array<f32, 16>)
    -> f32 {
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
    let depth = min(x.c_depth_terms, 8u);
    nephele_nt_begin(g, NepheleNtPass(beta, x.c_param_stride, group_stride, x.c_q, cols.x,
        cols.y), r.s);
    nephele_nc_features(stat);
    var sum = 0.0;
    for (var j = 0u; j < depth; j++) {
        sum += nephele_nt_acc[j] * p_x[j];
    }
    return sum;
}

// T, c and σ of group g at `at` (the runtime's `evaluate`); past the thickest slab T and σ
// continued by diffusion theory, c held.
fn nephele_evaluate(g: u32, at: NepheleSlabPoint) -> NepheleTransport {
    let c = nephele_nt_continued(at);
    nephele_nt_prepare(c.at);
    return nephele_nc_continued(g, c);
}

// T, c and σ of every order group at `at` (groups beyond the file's 0), the point's features
// built once: `nephele_evaluate` for each group.
fn nephele_evaluate_all(at: NepheleSlabPoint) -> array<NepheleTransport, 8> {
    let c = nephele_nt_continued(at);
    nephele_nt_prepare(c.at);
    var out: array<NepheleTransport, 8>;
    for (var g = 0u; g < min(nephele_ntt_index.groups, NEPHELE_MAX_GROUPS); g++) {
        out[g] = nephele_nc_continued(g, c);
    }
    return out;
}

// Group g at the prepared point, scaled past the thickest slab.
fn nephele_nc_continued(g: u32, c: NepheleNtContinued) -> NepheleTransport {
    var out = nephele_nc_evaluate(g);
    out.t *= nephele_nt_diffuse_scale(g, c);
    out.sigma *= select(c.spread, c.spread_diffuse, g + 1u == nephele_ntt_index.groups);
    return out;
}

// T, c and σ of group g at the prepared point (within the grid's thicknesses).
fn nephele_nc_evaluate(g: u32) -> NepheleTransport {
    let x = nephele_ntt_index;
    let r = nephele_nt_transport(g);
    var out = NepheleTransport(r.t, 0.0, 0.0, 0.0);
    if !(r.t > 0.0) || x.has_collector == 0u {
        return out;
    }
    // c and σ are held within the fitted depths.
    let u = nephele_nt_held(r.range, nephele_nt_pt.cell.u);
    let p_x = nephele_nt_legendre(2.0 * u - 1.0, min(x.c_depth_terms, 8u));
    let all = vec2<u32>(0u, 0xffffffffu);
    let sigma = nephele_exp(nephele_nc_part(g, 0u, all, r, p_x));
    let cz_main = nephele_nc_part(g, 1u, vec2<u32>(0u, x.cz_reach), r, p_x);
    let cz_reach = nephele_nc_part(g, 1u, vec2<u32>(x.cz_reach, 0xffffffffu), r, p_x);
    let cx = nephele_nc_part(g, 2u, all, r, p_x);
    out.c_x = sigma * cx;
    out.c_z = sigma * (cz_main + cz_reach / sigma);
    out.sigma = sigma;
    return out;
}
