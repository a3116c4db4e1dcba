// Order 1 — single scattering of the sun beam in the slab, T₁ = L/E⊥ (sr⁻¹), albedo 1 — from
// the phase function stored in the `.ntt` (nephele-runtime's `TransportTables::order1`):
//
//   T₁ = p(Θ) e^{−d/μ_L} (1 − e^{−a(t − d)}) / (1 + μ_V/μ_L),  a = 1/μ_L + 1/μ_V   (μ_V > 0),
//   T₁ = p(Θ) e^{−d/μ_L} (e^{bd} − 1) / (m/μ_L − 1),  m = −μ_V, b = 1/μ_L − 1/m     (μ_V < 0),
//   T₁ = p(Θ) e^{−d/μ_L} at the horizon,
//
// with m/μ_L − 1 and b from m − μ_L (no cancellation where the view looks down at the sun's
// angle), p between the stored nodes as the tabulated model has it (2π p sin θ linear in θ).
// Needs ntt.wgsl before it.

// The stored p at a cosine: θ among the nodes (degrees in the file), f = 2π p sin θ linear.
fn nephele_stored_phase(c: NepheleCosine) -> f32 {
    let a = nephele_cosine_angle(c);
    let to_rad = NEPHELE_PI / 180.0;
    let x = nephele_ntt_index;
    let lo = nephele_ntt_bracket(x.phase_theta, x.n_phase, a.x / to_rad);
    let ta = nephele_ntt_f32(x.phase_theta + lo) * to_rad;
    let tb = nephele_ntt_f32(x.phase_theta + lo + 1u) * to_rad;
    let fa = 2.0 * NEPHELE_PI * nephele_ntt_f32(x.phase + lo) * nephele_sin_cos(ta).x;
    let fb = 2.0 * NEPHELE_PI * nephele_ntt_f32(x.phase + lo + 1u) * nephele_sin_cos(tb).x;
    return nephele_phase_between(vec2<f32>(ta, fa), vec2<f32>(tb, fb), a);
}

// T₁ for a phase function of value p (albedo included) at `at`.
fn nephele_beam_scattered_once(p: f32, at: NepheleSlabPoint) -> f32 {
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
    let ratio_m1 = (m - at.mu_l) / at.mu_l;
    let bd = ratio_m1 / m * d;
    if abs(bd) < 1e-3 {
        return source * (d / m) * (1.0 + bd * 0.5 * (1.0 + bd / 3.0));
    }
    if bd < 1.0 {
        return source * nephele_exp_m1(bd) / ratio_m1;
    }
    return p * (nephele_exp(-d / m) - nephele_exp(-d / at.mu_l)) / ratio_m1;
}

// Order 1 at `at` (sr⁻¹, albedo 1): the runtime's `TransportTables::order1`.
fn nephele_order1(at: NepheleSlabPoint) -> f32 {
    if !nephele_in_slab(at) {
        return 0.0;
    }
    return nephele_beam_scattered_once(nephele_stored_phase(nephele_scattering_cosine(at)), at);
}
