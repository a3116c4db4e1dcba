//! Sun-lobe next-event estimation: multi-sample MIS over the last K directions of a path, with
//! one strategy per possible entry into the sun's forward-peak lobe.
//!
//! NEE at a collision x_N reached along d_N scores β ϖ p(s · d_N) T_r(x_N → sun) E_sun; with a
//! forward peak (10 µm Mie: p ≈ 200 sr⁻¹ within a degree of s, 0.08 sr⁻¹ on average) it is
//! heavy-tailed: runs of segments in the peak around the sun direction s — light that came from
//! the sun almost undeflected, the aureole — bring fireflies. A run is rare because it must be
//! *entered*: one wide-angle scattering into the peak (density p(d_{e−1} · d_e) small), after
//! which the peak keeps it there (each next segment with probability ≈ 0.4).
//!
//! So every collision x_m of the camera path launches a *sun-lobe walk*: its first direction is
//! drawn from p around s (density B = p̄(s · d)), the next ones from p around the previous one
//! like the camera path's own (density A = p̄(d_{i−1} · d_i)), and it goes on only while its
//! direction stays in the lobe (B ≥ τ, the cone around s holding `LOBE_MASS` of p), at most K
//! steps; each collision scores NEE for its order. For order N and the window of the last
//! L = min(K, N − 1) directions d_1 … d_L of a path that reaches x_N, the strategies are the
//! camera path (e = 0) and the walks entering at e = 1 … L (launched where d_e starts); with
//! π_0 = Π A_i, a walk entering at e samples the path with density
//!
//!   π_e = π_0 B_e / A_e · [B_i ≥ τ for e ≤ i < L] · c_e / c_0,
//!
//! c the probability that the camera path survived roulette up to where the strategy leaves it
//! (q_m per order, deterministic). Flights are delta-tracked in every strategy, so their
//! densities are the same and cancel. Each strategy's sample scores its own estimate times the
//! balance heuristic w_e = π_e / Σ_{e′} π_{e′} (Veach's multi-sample MIS: one sample per strategy,
//! Σ w = 1, and the camera path covers every path, so the sum is unbiased). A walk's estimate at
//! its i-th collision is
//!
//!   β_m ϖ^i [p_k(d_m · d′_1) / p̄(s · d′_1)] Π_{1<i′≤i} [p_k(d′_{i′−1} · d′_{i′}) / p̄(d′_{i′−1} · d′_{i′})]
//!       · p_k(s · d′_i) T_r E_sun
//!
//! (β_m the camera path's throughput after x_m's albedo and roulette, p_k per channel). For a run
//! entered at e inside the window the camera path's weight is at most A_e / B_e, so the spike
//! p(s · d_N) is cut to about p(wide angle) whatever the run's length up to K; only runs
//! entered more than K directions back keep a spike divided by their count of valid entries. A
//! diffuse path has almost never an earlier direction in the lobe, so mostly only e = L counts:
//! the two-vertex MIS w_0 = A_L / (A_L + B_L). The walks stop as soon as they leave the lobe, so
//! they take fewer than 2 steps on average whatever K is (the first direction lands in the lobe
//! with probability ½ by construction, a later one stays there less often). K = 1 is the
//! two-vertex NEE of earlier versions; K = 0 is plain NEE.

use nephele_runtime::PhaseFunction;

/// Most steps of a sun-lobe walk (and directions of a window).
pub const MAX_STEPS: usize = 32;

/// The share of the phase function's mass inside the lobe (the cone around s where walks go on).
pub const LOBE_MASS: f64 = 0.5;

/// One direction of a window: its density from the phase function around the previous
/// direction (`a`, 1/sr) and around the sun (`b`, 1/sr), channel means.
#[derive(Clone, Copy, Debug, Default)]
pub struct Step {
    /// p̄(d_{i−1} · d_i).
    pub a: f64,
    /// p̄(s · d_i).
    pub b: f64,
}

/// The sun-lobe estimator's settings.
#[derive(Clone, Copy, Debug)]
pub struct SunLobe {
    /// K: most steps of a walk, directions of the MIS window (0: plain NEE).
    pub steps: usize,
    /// τ: the lobe is where p̄(s · d) ≥ τ (1/sr).
    pub threshold: f64,
}

impl SunLobe {
    /// Plain next-event estimation.
    pub const OFF: SunLobe = SunLobe {
        steps: 0,
        threshold: f64::INFINITY,
    };

    /// K steps with the lobe of the channels' mean phase function holding `LOBE_MASS`.
    pub fn new(steps: usize, phases: &[&(dyn PhaseFunction<f64> + Sync)]) -> Self {
        Self {
            steps: steps.min(MAX_STEPS),
            threshold: lobe_threshold(phases, LOBE_MASS),
        }
    }
}

/// τ such that the cone {p̄(s · d) ≥ τ} around the forward direction holds `mass` of p̄ (for a
/// phase function decreasing away from forward; 2π ∫ p̄ dμ on a fine grid in θ from 0).
pub fn lobe_threshold(phases: &[&(dyn PhaseFunction<f64> + Sync)], mass: f64) -> f64 {
    let mean = |mu: f64| phases.iter().map(|p| p.eval(mu)).sum::<f64>() / phases.len() as f64;
    let n = 20_000;
    let dt = std::f64::consts::PI / n as f64;
    let mut acc = 0.0;
    for i in 0..n {
        let (t0, t1) = (i as f64 * dt, (i + 1) as f64 * dt);
        // Midpoint rule on dμ = sin θ dθ.
        acc += 2.0 * std::f64::consts::PI * mean((0.5 * (t0 + t1)).cos()) * (t0.cos() - t1.cos());
        if acc >= mass {
            return mean(t1.cos());
        }
    }
    0.0
}

/// The camera path's last `MAX_STEPS` directions (a ring, oldest overwritten).
#[derive(Clone, Copy, Debug)]
pub struct History {
    steps: [Step; MAX_STEPS],
    /// Directions pushed so far.
    len: usize,
}

impl Default for History {
    fn default() -> Self {
        Self {
            steps: [Step::default(); MAX_STEPS],
            len: 0,
        }
    }
}

impl History {
    /// Records the direction the path arrived along at its latest collision.
    pub fn push(&mut self, step: Step) {
        self.steps[self.len % MAX_STEPS] = step;
        self.len += 1;
    }

    /// The last `n` directions, oldest first, into `out` (n ≤ MAX_STEPS and ≤ those pushed).
    pub fn last(&self, n: usize, out: &mut [Step]) {
        debug_assert!(n <= MAX_STEPS && n <= self.len);
        for (i, o) in out[..n].iter_mut().enumerate() {
            *o = self.steps[(self.len - n + i) % MAX_STEPS];
        }
    }
}

/// The balance-heuristic weight of `strategy` (0: the camera path; e ≥ 1: the walk entering at
/// the window's e-th direction) for a window `d` (oldest first) ending at the collision of
/// order `n`, lobe threshold `tau` and roulette survival probability `q(order)`.
pub fn mis_weight(d: &[Step], strategy: usize, n: u32, tau: f64, q: impl Fn(u32) -> f64) -> f64 {
    let l = d.len();
    if l == 0 {
        return 1.0;
    }
    // suffix[i] = Π_{i′ ≥ i} A (0-based); π_e = prefix(e−1) · B_e · suffix[e] (e 1-based).
    let mut suffix = [1.0; MAX_STEPS + 1];
    for i in (0..l).rev() {
        suffix[i] = suffix[i + 1] * d[i].a;
    }
    // The entry at e (1-based) is launched at order first + e − 2; its survival from the
    // window's start is Π_{m=first}^{first+e−2} q_m, the camera path's Π_{m=first}^{n−1} q_m.
    let first = n + 1 - l as u32;
    let survival = survival_products(l, first, &q);
    // valid_e: the walk stays in the lobe from e to l − 1 (1-based): scanned from the end.
    let mut valid = [false; MAX_STEPS + 1];
    valid[l] = true;
    for e in (1..l).rev() {
        valid[e] = valid[e + 1] && d[e - 1].b >= tau;
    }
    let camera = suffix[0] * survival[l];
    let (mut total, mut mine) = (camera, if strategy == 0 { camera } else { 0.0 });
    let mut prefix = 1.0;
    for e in 1..=l {
        if valid[e] {
            let pi = prefix * d[e - 1].b * suffix[e] * survival[e - 1];
            total += pi;
            if e == strategy {
                mine = pi;
            }
        }
        prefix *= d[e - 1].a;
    }
    if total > 0.0 {
        mine / total
    } else {
        0.0
    }
}

/// survival[i] = Π_{m=first}^{first+i−1} q_m for i < l, and survival[l] = survival[l − 1] (the
/// camera path needs the roulette of orders first … n − 1 only).
fn survival_products(l: usize, first: u32, q: &impl Fn(u32) -> f64) -> [f64; MAX_STEPS + 1] {
    let mut s = [1.0; MAX_STEPS + 1];
    for i in 1..l {
        s[i] = s[i - 1] * q(first + i as u32 - 1);
    }
    s[l] = s[l - 1];
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn window(seed: u64, l: usize) -> Vec<Step> {
        let mut x = seed;
        let mut next = || {
            x = crate::stats::splitmix64(x);
            (x >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..l)
            .map(|_| Step {
                a: 1e-2 + 300.0 * next().powi(4),
                b: 1e-2 + 300.0 * next().powi(4),
            })
            .collect()
    }

    #[test]
    fn weights_sum_to_one_with_and_without_roulette() {
        for l in 0..=MAX_STEPS {
            for seed in 0..50 {
                let d = window(seed * 31 + l as u64, l);
                for tau in [0.0, 5.0, f64::INFINITY] {
                    for q in [|_: u32| 1.0, |m: u32| if m % 3 == 0 { 0.1 } else { 1.0 }] {
                        let sum: f64 = (0..=l).map(|e| mis_weight(&d, e, 40, tau, q)).sum();
                        assert!((sum - 1.0).abs() < 1e-12, "L {l}: Σ w = {sum}");
                    }
                }
            }
        }
    }

    #[test]
    fn one_step_is_the_two_vertex_balance_heuristic() {
        let d = [Step { a: 3.0, b: 40.0 }];
        let w0 = mis_weight(&d, 0, 5, 1.0, |_| 1.0);
        assert!((w0 - 3.0 / 43.0).abs() < 1e-15);
    }

    #[test]
    fn a_run_in_the_lobe_is_weighted_by_its_entry() {
        // A wide-angle scattering into the peak (A = 0.05, B = 200) followed by five segments
        // in the peak (A = B = 200): the camera path keeps about A_e / B_e of its NEE.
        let mut d = vec![Step { a: 0.1, b: 0.1 }, Step { a: 0.05, b: 200.0 }];
        d.extend([Step { a: 200.0, b: 200.0 }; 5]);
        let w0 = mis_weight(&d, 0, 20, 10.0, |_| 1.0);
        assert!(w0 < 0.05 / 200.0 * 1.01, "w0 = {w0}");
        // Out of the lobe in the middle: the entry's walk would have stopped there.
        d[4].b = 1.0;
        let w0 = mis_weight(&d, 0, 20, 10.0, |_| 1.0);
        assert!(w0 > 0.1, "w0 = {w0}");
    }

    #[test]
    fn history_returns_the_last_directions_oldest_first() {
        let mut h = History::default();
        for i in 0..(MAX_STEPS + 11) {
            h.push(Step {
                a: i as f64,
                b: 0.0,
            });
        }
        let mut out = [Step::default(); MAX_STEPS];
        h.last(3, &mut out);
        let n = (MAX_STEPS + 11) as f64;
        assert_eq!([out[0].a, out[1].a, out[2].a], [n - 3.0, n - 2.0, n - 1.0]);
    }
}
