// Order 1 — single scattering of the sun beam in the slab, T₁ = L/E⊥ (sr⁻¹), albedo 1 — in
// WGSL, from the phase function stored in a `.ntt` (nephele-runtime's `TransportTables::order1`):
//
//   T₁ = p(Θ) e^{−d/μ_L} (1 − e^{−a(t − d)}) / (1 + μ_V/μ_L),  a = 1/μ_L + 1/μ_V   (μ_V > 0),
//   T₁ = p(Θ) e^{−d/μ_L} (e^{bd} − 1) / (m/μ_L − 1),  m = −μ_V, b = 1/μ_L − 1/m     (μ_V < 0),
//   T₁ = p(Θ) e^{−d/μ_L} at the horizon, with 1 − cos Θ = |ω_L − ω_V|²/2,
//
// p between the stored nodes as the tabulated model has it (2π p sin θ linear in θ). Needs
// `Cosine`, `nephele_asin`, `nephele_exp` and `PI` from phase.wgsl.
//
// The `.ntt` is uploaded whole as `array<u32>` (`nephele_wgsl::NttGpu::words`); the index
// (`NttGpu::index`: word offsets of the arrays read here and the phase table's length) is a
// uniform. `nephele_wgsl::order1(group, binding)` gives this source with the bindings chosen:
// the words at `binding`, the index at `binding + 1`.

struct NttIndex {
    phase_theta: u32,
    phase: u32,
    n_phase: u32,
    pad: u32,
}

@group(NEPHELE_NTT_GROUP) @binding(NEPHELE_NTT_BINDING)
var<storage, read> nephele_ntt: array<u32>;
@group(NEPHELE_NTT_GROUP) @binding(NEPHELE_NTT_INDEX_BINDING)
var<uniform> nephele_ntt_index: NttIndex;

fn ntt_f32(word: u32) -> f32 {
    return bitcast<f32>(nephele_ntt[word]);
}

// A point of the slab: depth d and thickness t (mean free paths), view cosine μ_V (> 0: the
// light goes up), view azimuth ψ_V (radians, from the sun's horizontal travel), sun cosine μ_L.
struct SlabPoint {
    depth: f32,
    thickness: f32,
    mu_v: f32,
    psi_v: f32,
    mu_l: f32,
}

// eˣ − 1 without the cancellation of small x.
fn nephele_exp_m1(x: f32) -> f32 {
    if abs(x) < 0.01 {
        return x * (1.0 + x / 2.0 * (1.0 + x / 3.0 * (1.0 + x / 4.0 * (1.0 + x / 5.0
            * (1.0 + x / 6.0)))));
    }
    return nephele_exp(x) - 1.0;
}

fn scattering_cosine(at: SlabPoint) -> Cosine {
    let sin_l = sqrt(clamp(1.0 - at.mu_l * at.mu_l, 0.0, 1.0));
    let sin_v = sqrt(clamp(1.0 - at.mu_v * at.mu_v, 0.0, 1.0));
    let s = sin(at.psi_v);
    let c = cos(at.psi_v);
    let dx = sin_v * s;
    let dz = sin_l - sin_v * c;
    let dd = at.mu_l + at.mu_v;
    return cosine_from_one_minus_mu(clamp(0.5 * (dx * dx + dz * dz + dd * dd), 0.0, 2.0));
}

// The stored p at a cosine: θ among the nodes (degrees in the file), f = 2π p sin θ linear.
fn stored_phase(c: Cosine) -> f32 {
    let omm = clamp(c.one_minus_mu, 0.0, 2.0);
    var theta: f32;
    if c.mu >= 0.0 {
        theta = 2.0 * nephele_asin(sqrt(omm / 2.0));
    } else {
        theta = PI - 2.0 * nephele_asin(sqrt(clamp(1.0 + c.mu, 0.0, 1.0) / 2.0));
    }
    let sin_t = sqrt(omm * (2.0 - omm));
    let to_rad = PI / 180.0;
    let x = nephele_ntt_index;
    var lo = 0u;
    var hi = max(x.n_phase, 2u) - 1u;
    let deg = theta / to_rad;
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if ntt_f32(x.phase_theta + mid) <= deg {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let ta = ntt_f32(x.phase_theta + lo) * to_rad;
    let tb = ntt_f32(x.phase_theta + lo + 1u) * to_rad;
    let fa = 2.0 * PI * ntt_f32(x.phase + lo) * sin(ta);
    let fb = 2.0 * PI * ntt_f32(x.phase + lo + 1u) * sin(tb);
    let h = tb - ta;
    if sin_t <= 0.0 {
        return abs(fb - fa) / h / (2.0 * PI);
    }
    return (fa + (fb - fa) * (theta - ta) / h) / (2.0 * PI * sin_t);
}

// T₁ for a phase function of value p (albedo included) at `at`.
fn beam_scattered_once(p: f32, at: SlabPoint) -> f32 {
    let d = at.depth;
    let t = at.thickness;
    let source = p * nephele_exp(-d / at.mu_l);
    if at.mu_v == 0.0 {
        return source;
    }
    if at.mu_v > 0.0 {
        if t - d <= 0.0 {
            return 0.0;
        }
        let m = at.mu_v;
        let a = 1.0 / at.mu_l + 1.0 / m;
        return source * -nephele_exp_m1(-a * (t - d)) / (1.0 + m / at.mu_l);
    }
    if d <= 0.0 {
        return 0.0;
    }
    let m = -at.mu_v;
    let bd = (1.0 / at.mu_l - 1.0 / m) * d;
    if abs(bd) < 1e-3 {
        return source * (d / m) * (1.0 + bd * 0.5 * (1.0 + bd / 3.0));
    }
    if bd < 1.0 {
        return source * nephele_exp_m1(bd) / (m / at.mu_l - 1.0);
    }
    return p * (nephele_exp(-d / m) - nephele_exp(-d / at.mu_l)) / (m / at.mu_l - 1.0);
}

// Order 1 at `at` (sr⁻¹, albedo 1): the runtime's `TransportTables::order1`.
fn order1(at: SlabPoint) -> f32 {
    return beam_scattered_once(stored_phase(scattering_cosine(at)), at);
}
