//! The WGSL transport tables (nephele_wgsl::tables: T of each order group and order 1 from a
//! `.ntt` in a storage buffer) run on a real Vulkan driver (Mesa's lavapipe on the CPU in CI)
//! against the Rust runtime at 10⁵ points over the whole domain a caller can reach: both faces,
//! the horizon (±0), views straight up and down, grazing and overhead suns, t = 0.3 … 200
//! (beyond the grid's 0.5 … 128), every azimuth.
//!
//! `cargo test --release -p nephele-wgsl --test tables -- --nocapture` prints the agreement.

mod common;
use common::{gpu, pipeline, run_kernel};
use nephele_runtime::transport::{SlabPoint, Transport, TransportTables};
use std::time::Instant;

const SHIPPED: &[u8] = include_bytes!("../../runtime/tables/mie10um/transport.ntt");

/// The test kernel: per point order 1 then T of every group.
const KERNEL: &str = include_str!("tables_kernel.wgsl");

/// Points over the whole domain (xorshift, fixed seed): both faces, the horizon (±0), views
/// straight up and down, overhead and grazing suns, t = 0.3 … 200, every azimuth.
fn points(n: usize) -> Vec<SlabPoint<f32>> {
    let mut rng = nephele_stats::XorShift64::new(0x2545_F491_4F6C_DD1D);
    let mut r = || rng.unit_f32();
    (0..n)
        .map(|i| {
            let t = [0.3, 128.0, 200.0]
                .get(i % 13)
                .copied()
                .unwrap_or(0.5 * 256f32.powf(r()));
            let depth = match i % 7 {
                0 => 0.0,
                1 => t,
                _ => t * r(),
            };
            let mu_v = match i % 11 {
                0 => 0.0,
                1 => -0.0,
                2 => 1.0,
                3 => -1.0,
                _ => 2.0 * r() - 1.0,
            };
            SlabPoint {
                depth,
                thickness: t,
                mu_v,
                psi_v: std::f32::consts::PI * (2.0 * r() - 1.0),
                mu_l: match i % 17 {
                    0 => 1.0,
                    _ => 0.02 + 0.98 * r(),
                },
            }
        })
        .collect()
}

/// The tables evaluated in f64 wherever the runtime computes in f32 (the runtime's own steps
/// otherwise): the reference by which both f32 implementations are judged, since near a line's
/// zero in the depth continuation or a glory's swing in the phase function every f32
/// evaluation is ill-conditioned.
struct Wide {
    shape: nephele_runtime::fitting::LogAdditive,
    q: usize,
    groups: usize,
    mu_l: Vec<f64>,
    mu_v: Vec<f64>,
    thickness: Vec<f64>,
    beta: Vec<f64>,
    u_range: Vec<f32>,
    span: Vec<f64>,
    ceiling: Option<Vec<f64>>,
    phase_theta: Vec<f64>,
    phase: Vec<f64>,
    halo: Option<WideHalo>,
}

/// The halo around the transmitted beam, in f64.
struct WideHalo {
    edges: Vec<f64>,
    groups: usize,
    planes: usize,
    values: Vec<f64>,
}

impl WideHalo {
    /// e^h of group `g` at `cell`, `near_t` among `nt` thickness nodes (1 outside the halo).
    fn factor(
        &self,
        g: usize,
        cell: &nephele_runtime::fitting::Cell<f64>,
        near_t: nephele_runtime::fitting::Lerp<f64>,
        (nt, nl): (usize, usize),
    ) -> f64 {
        let nb = self.edges.len() - 1;
        let (last, deg) = (self.edges[nb], cell.theta.to_degrees());
        if g >= self.groups || !(cell.at.mu_v < 0.0) || !(deg < last) {
            return 1.0;
        }
        let centre = |b: usize| (0.5 * (self.edges[b].powi(2) + self.edges[b + 1].powi(2))).sqrt();
        let annuli = if deg >= centre(nb - 1) {
            vec![(nb - 1, (last - deg) / (last - centre(nb - 1)))]
        } else if deg <= centre(0) {
            vec![(0, 1.0)]
        } else {
            let b = (0..nb - 1).rfind(|&b| centre(b) <= deg).unwrap_or(0);
            let w = (deg - centre(b)) / (centre(b + 1) - centre(b));
            vec![(b, 1.0 - w), (b + 1, w)]
        };
        let x = cell.u.clamp(0.0, 1.0) * (self.planes - 1) as f64;
        let j0 = (x as usize).min(self.planes - 1);
        let planes = [
            (j0, 1.0 - (x - j0 as f64)),
            ((j0 + 1).min(self.planes - 1), x - j0 as f64),
        ];
        let mut h = 0.0;
        near_t.each(|it, wt| {
            cell.l.each(|il, wl| {
                for (j, wj) in planes {
                    let row = ((((g * nt + it) * nl + il) * self.planes) + j) * nb;
                    for &(b, wb) in &annuli {
                        h += wt * wl * wj * wb * self.values[row + b];
                    }
                }
            })
        });
        h.exp()
    }
}

impl Wide {
    fn new(bytes: &[u8]) -> Self {
        use nephele_runtime::container::Container;
        use nephele_runtime::fitting::{names, LogAdditive};
        let c = Container::from_bytes(bytes).unwrap();
        let array = |name: &str| -> Option<Vec<f64>> {
            c.find(name).map(|a| a.iter().map(f64::from).collect())
        };
        let form = array(names::FORM).unwrap();
        assert!(c.version() >= 2, "feature-major β");
        Self {
            shape: LogAdditive {
                legendre: form[0] as usize,
                harmonics: form[1] as usize,
                theta_nodes: form[2] as usize,
                pairs: form[3] == 1.0,
                cross: form.get(5).map_or(0, |a| *a as usize),
            },
            q: form[4] as usize,
            groups: array(names::GROUP_FIRST).unwrap().len(),
            mu_l: array(names::MU_L_NODES).unwrap(),
            mu_v: array(names::MU_V_NODES).unwrap(),
            thickness: array(names::THICKNESS).unwrap(),
            beta: array(names::BETA).unwrap(),
            u_range: c.find(names::U_RANGE).unwrap().iter().collect(),
            span: array(names::LN_T_RANGE).unwrap(),
            ceiling: array(names::T_CEILING),
            phase_theta: array(names::PHASE_THETA).unwrap(),
            phase: array(names::PHASE).unwrap(),
            halo: array(names::HALO_SHAPE).map(|shape| WideHalo {
                edges: array(names::HALO_EDGES).unwrap(),
                groups: shape[0] as usize,
                planes: shape[1] as usize,
                values: array(names::HALO).unwrap(),
            }),
        }
    }

    /// T of group `g` at `at`; under a sun below the grid's lowest μ₀ read under μ₀ with T
    /// scaled by μ_L/μ₀, past the thickest slab continued as the runtime does
    /// (runtime/src/transport/thick.rs), in f64 with g of the tables' phase function.
    fn transport(&self, g: usize, at: &SlabPoint<f32>) -> f64 {
        let mut p = at.to_f64();
        let mut sun = 1.0;
        if p.mu_l > 0.0 && p.mu_l < self.mu_l[0] {
            sun = p.mu_l / self.mu_l[0];
            p.mu_l = self.mu_l[0];
        }
        sun * self.transport_held_sun(g, &p)
    }

    /// [`Self::transport`] under a sun within the grid.
    fn transport_held_sun(&self, g: usize, p: &SlabPoint<f64>) -> f64 {
        let p = *p;
        let t_max = *self.thickness.last().unwrap();
        if !(p.thickness > t_max && p.depth >= 0.0 && p.depth <= p.thickness && p.mu_l > 0.0) {
            return self.transport_within(g, &p);
        }
        let tables = nephele_runtime::transport::TransportTables::from_bytes(SHIPPED).unwrap();
        let g_mean = (tables.mean_cosine() as f64).min(0.999);
        let half = 0.5 * t_max;
        let (z_s, z_e) = (
            (p.mu_l / (1.0 - g_mean)).min(half),
            2.0 / (3.0 * (1.0 - g_mean)),
        );
        let fluence =
            |z: f64, t: f64| (z.min(z_s) + z_e) * (t + z_e - z.max(z_s)) / (t + 2.0 * z_e);
        let (d, h) = (p.depth, p.thickness - p.depth);
        let depth = if d <= half {
            d
        } else if h <= half {
            t_max - h
        } else {
            half
        };
        let diffuse = fluence(d, p.thickness) / fluence(depth, t_max);
        let scale = if g + 1 == self.groups {
            diffuse
        } else {
            diffuse.min(1.0)
        };
        let inside = SlabPoint {
            thickness: t_max,
            depth,
            ..p
        };
        self.transport_within(g, &inside) * scale
    }

    /// T of group `g` at `p` within the grid's thicknesses (extrapolated beyond).
    fn transport_within(&self, g: usize, p: &SlabPoint<f64>) -> f64 {
        use nephele_runtime::fitting::{
            depth_polynomial, ln_boundary, ln_t_position, unpack_u_range, Cell, FittedDepths,
            Legendre, Lerp, CEILING_FACTOR, MAX_LEGENDRE,
        };
        let p = *p;
        let (t, d) = (p.thickness, p.depth);
        if !(t > 0.0 && d >= 0.0 && d <= t) {
            return 0.0;
        }
        let Some(offset) = ln_boundary(&p) else {
            return 0.0;
        };
        let (nl, nm, nt) = (self.mu_l.len(), self.mu_v.len(), self.thickness.len());
        let stretch = 0.3 * (0.65 * t.ln()).exp();
        let u = ((1.0 + stretch.exp_m1() * d / t).ln() / stretch).clamp(0.0, 1.0);
        let cell = Cell::new(
            p,
            Lerp::between(&self.mu_l, p.mu_l),
            Lerp::between(&self.mu_v, p.mu_v),
            u,
        );
        let near_t = Lerp::between(&self.thickness, t);
        let s = ln_t_position((self.span[2 * g], self.span[2 * g + 1]), t.ln());
        let lq: Vec<f64> = Legendre::new(s).take(self.q).collect();
        let coef = |col: usize| -> f64 {
            let at = (col * self.groups + g) * self.q;
            self.beta[at..at + self.q]
                .iter()
                .zip(&lq)
                .map(|(b, l)| b * l)
                .sum()
        };
        let (mut corners, mut tops) = (Vec::new(), Vec::new());
        near_t.each(|it, wt| {
            cell.l.each(|il, wl| {
                tops.push(it * nl + il);
                cell.v.each(|m, wm| {
                    let packed = self.u_range[g * nt * nl * nm + (it * nl + il) * nm + m];
                    let (a, b) = unpack_u_range(packed);
                    corners.push((wt * wl * wm, a as f64, b as f64));
                })
            })
        });
        let Some(range) = FittedDepths::of(corners) else {
            return 0.0;
        };
        let mut dj = [0.0f64; MAX_LEGENDRE];
        let (shape, terms) = (self.shape, self.shape.depth_terms());
        if !shape.for_each_feature_in_depth(&cell, nm, nl, |col, v, j| dj[j] += v * coef(col)) {
            return 0.0;
        }
        let v = range.share * (offset + depth_polynomial(&dj, terms, u, t, &range)).exp();
        let capped = match &self.ceiling {
            Some(top) => {
                let most = tops
                    .iter()
                    .map(|k| top[g * nt * nl + k])
                    .fold(0.0, f64::max);
                v.min(CEILING_FACTOR * most)
            }
            None => v,
        };
        capped
            * self
                .halo
                .as_ref()
                .map_or(1.0, |h| h.factor(g, &cell, near_t, (nt, nl)))
    }

    /// Order 1 at `at` (albedo 1), the stored p between its nodes with 2π p sin θ linear in θ.
    fn order1(&self, at: &SlabPoint<f32>) -> f64 {
        use nephele_runtime::phase::Cosine;
        use nephele_runtime::transport::{single_scattering, PhaseValue};
        struct Stored<'a>(&'a Wide);
        impl PhaseValue<f64> for Stored<'_> {
            fn value(&self, c: Cosine<f64>) -> f64 {
                let omm = c.one_minus_mu.clamp(0.0, 2.0);
                let theta = if c.mu >= 0.0 {
                    2.0 * (omm / 2.0).sqrt().asin()
                } else {
                    std::f64::consts::PI - 2.0 * ((1.0 + c.mu).clamp(0.0, 1.0) / 2.0).sqrt().asin()
                };
                let sin = (omm * (2.0 - omm)).sqrt();
                let nodes = &self.0.phase_theta;
                let deg = theta.to_degrees();
                let i = nodes
                    .partition_point(|v| *v <= deg)
                    .clamp(1, nodes.len() - 1)
                    - 1;
                let node = |k: usize| {
                    let t = nodes[k].to_radians();
                    (t, 2.0 * std::f64::consts::PI * self.0.phase[k] * t.sin())
                };
                let ((ta, fa), (tb, fb)) = (node(i), node(i + 1));
                let two_pi = 2.0 * std::f64::consts::PI;
                if sin <= 0.0 {
                    return (fb - fa).abs() / (tb - ta) / two_pi;
                }
                (fa + (fb - fa) * (theta - ta) / (tb - ta)) / (two_pi * sin)
            }
        }
        single_scattering(&Stored(self), 1.0, &at.to_f64())
    }
}

/// Runs the kernel on `points`: per point order 1 then T of every group; and the seconds the
/// dispatch took (upload and read-back included).
fn on_gpu(points: &[SlabPoint<f32>], groups: usize) -> (Vec<f32>, f64) {
    let ntt = nephele_wgsl::ntt_for_gpu(SHIPPED).expect("the shipped tables");
    let source = format!(
        "{}\n{}\n{}",
        nephele_wgsl::PHASE,
        nephele_wgsl::tables(0, 3),
        KERNEL
    );
    let kernel = pipeline("tables", &source);
    let flat: Vec<f32> = points
        .iter()
        .flat_map(|p| [p.thickness, p.mu_l, p.depth, p.mu_v, p.psi_v])
        .collect();
    let job = [points.len() as u32, groups as u32, 0, 0];
    let start = Instant::now();
    let out = run_kernel(
        &kernel,
        job,
        &flat,
        Some(&ntt),
        4 * (4 * groups as u64 + 1) * points.len() as u64,
        points.len() as u32,
    );
    let seconds = start.elapsed().as_secs_f64();
    (bytemuck::cast_slice(&out).to_vec(), seconds)
}

/// The distances of one quantity's values where the runtime's value is above 1e-6 of its
/// largest: the GPU's and the runtime's from the f64 evaluation of the same tables, the GPU's
/// from the runtime's (relative, sorted); and how many values are zero on one side only.
struct Agreement {
    gpu: Vec<f64>,
    runtime: Vec<f64>,
    between: Vec<f64>,
    zero_mismatch: usize,
}

impl Agreement {
    fn of(got: impl Iterator<Item = f32>, want: &[f32], wide: &[f64]) -> Self {
        let top = want.iter().fold(0.0f32, |a, &b| a.max(b));
        let mut a = Agreement {
            gpu: Vec::new(),
            runtime: Vec::new(),
            between: Vec::new(),
            zero_mismatch: 0,
        };
        for (i, (o, w)) in got.zip(want).enumerate() {
            // Zero where the runtime's value counts, or not zero where the runtime's is
            // (no medium behind the viewpoint, no fitted cells): below f32's normal range a
            // GPU may flush subnormal steps to zero, which is no mismatch.
            if *w > 1e-6 * top && o == 0.0 || *w == 0.0 && o != 0.0 {
                a.zero_mismatch += 1;
            }
            if *w > 1e-6 * top {
                a.gpu.push((o as f64 - wide[i]).abs() / wide[i]);
                a.runtime.push((*w as f64 - wide[i]).abs() / wide[i]);
                a.between.push(((o - w) / w).abs() as f64);
            }
        }
        for v in [&mut a.gpu, &mut a.runtime, &mut a.between] {
            v.sort_by(f64::total_cmp);
        }
        a
    }
}

/// The median, 99th and 99.9th percentiles and the largest of the sorted `v`.
fn row(v: &[f64]) -> String {
    format!(
        "median {:.1e}, 99 % {:.1e}, 99.9 % {:.1e}, max {:.1e}",
        quantile(v, 0.5),
        quantile(v, 0.99),
        quantile(v, 0.999),
        quantile(v, 1.0)
    )
}

/// The value below which a share `p` of the sorted `v` lies.
fn quantile(v: &[f64], p: f64) -> f64 {
    v.get(((v.len() as f64 * p) as usize).min(v.len().saturating_sub(1)))
        .copied()
        .unwrap_or(0.0)
}

/// Order 1 and T of every group on the GPU from the shipped `.ntt` against the runtime and
/// against the f64 evaluation of the same tables, wherever the runtime's value is above 1e-6 of
/// its largest. Two f32 evaluations of the log-additive form cannot agree to 1e-5 everywhere:
/// ln T sums some 50 terms of up to ±20, and where the depth continuation reads a line near its
/// zero (a face just ahead) or the phase function swings (the glory), the runtime's own f32 is
/// up to 2e-3 from f64. So the GPU is held to the runtime's own accuracy: its distance from
/// f64 at the 99th percentile and at most within twice the runtime's (+ 2e-6, the sums' order);
/// and zero exactly where the runtime is.
#[test]
fn tables_on_the_gpu_follow_the_runtime() {
    let tables = TransportTables::from_bytes(SHIPPED).unwrap();
    let groups = tables.groups();
    let pts = points(100_000);
    let (got, gpu_s) = on_gpu(&pts, groups);
    let reference = Wide::new(SHIPPED);
    let stride = 4 * groups + 1;
    println!("adapter: {}", gpu().adapter);
    let mut failures = Vec::new();
    for q in 0..=groups {
        let want: Vec<f32> = pts
            .iter()
            .map(|p| match q {
                0 => tables.order1(p),
                g => tables.transport(g - 1, p),
            })
            .collect();
        let wide: Vec<f64> = pts
            .iter()
            .map(|p| match q {
                0 => reference.order1(p),
                g => reference.transport(g - 1, p),
            })
            .collect();
        let column = if q == 0 { 0 } else { 1 + 4 * (q - 1) };
        let a = Agreement::of(
            got.iter().skip(column).step_by(stride).copied(),
            &want,
            &wide,
        );
        let name = match q {
            0 => "order 1".to_string(),
            g => format!(
                "T of group {} (orders ≥ {})",
                g - 1,
                tables.group_first_order(g - 1).unwrap()
            ),
        };
        let within = a.between.partition_point(|&d| d <= 1e-5);
        println!(
            "{name} ({} values above 1e-6 of the largest; {} zero/non-zero mismatches):\n  \
             GPU from f64:     {}\n  runtime from f64: {}\n  GPU from runtime: {} \
             ({:.2} % within 1e-5)",
            a.gpu.len(),
            a.zero_mismatch,
            row(&a.gpu),
            row(&a.runtime),
            row(&a.between),
            100.0 * within as f64 / a.between.len().max(1) as f64
        );
        // The GPU as close to the truth as the runtime's own f32: its 99th percentile and its
        // largest distance from f64 within twice the runtime's (+ 2e-6 for the sums' order).
        let close = |p: f64| quantile(&a.gpu, p) <= 2.0 * quantile(&a.runtime, p) + 2e-6;
        if !(close(0.99) && close(1.0)) || a.zero_mismatch > 0 {
            failures.push(name);
        }
    }
    // c and σ against the runtime's, where T is above 1e-6 of its largest: σ relative, c in
    // units of σ (c crosses zero); 99 % within 1e-5.
    let mut evaluated = vec![Transport::default(); groups];
    let (mut d_sigma, mut d_c, mut zero) = (Vec::new(), Vec::new(), 0);
    let tops: Vec<f32> = (0..groups)
        .map(|g| {
            pts.iter()
                .map(|p| tables.transport(g, p))
                .fold(0.0f32, f32::max)
        })
        .collect();
    for (i, p) in pts.iter().enumerate() {
        tables.evaluate_all(p, &mut evaluated);
        for (g, w) in evaluated.iter().enumerate() {
            let o = &got[stride * i + 1 + 4 * g..stride * i + 5 + 4 * g];
            // σ zero on one side only where T counts, or σ where the runtime has no light
            // (a subnormal T flushed to zero on the GPU takes its c and σ along: not counted).
            let counts = w.t > 1e-6 * tops[g];
            if counts && (w.sigma == 0.0) != (o[3] == 0.0) || w.t == 0.0 && o[3] != 0.0 {
                zero += 1;
            }
            if w.t > 1e-6 * tops[g] && w.sigma > 0.0 {
                d_sigma.push(((o[3] - w.sigma) / w.sigma).abs() as f64);
                let dc = (o[1] - w.c_x).abs().max((o[2] - w.c_z).abs());
                d_c.push((dc / w.sigma) as f64);
            }
        }
    }
    for v in [&mut d_sigma, &mut d_c] {
        v.sort_by(f64::total_cmp);
    }
    println!(
        "collector, every group ({} values; {zero} zero/non-zero mismatches of σ):\n  \
         σ, GPU from runtime (relative): {}\n  c, GPU from runtime (in σ):     {}",
        d_sigma.len(),
        row(&d_sigma),
        row(&d_c)
    );
    if zero > 0 || quantile(&d_sigma, 0.99) > 1e-5 || quantile(&d_c, 0.99) > 1e-5 {
        failures.push("collector".into());
    }
    // A record, not a GPU claim: lavapipe runs the kernel on this machine's CPU.
    let start = Instant::now();
    let mut sink = vec![0.0f32; groups];
    for p in &pts {
        tables.transport_all(p, &mut sink);
        std::hint::black_box(&sink);
    }
    let cpu_s = start.elapsed().as_secs_f64();
    println!(
        "T of all {groups} groups and order 1 at {} points: {:.2e} points/s on {} (one dispatch, \
         upload and read-back included) beside the runtime's T of all groups on one CPU core: \
         {:.2e} points/s",
        pts.len(),
        pts.len() as f64 / gpu_s,
        gpu().adapter,
        pts.len() as f64 / cpu_s
    );
    assert!(
        failures.is_empty(),
        "beyond 1e-5 or zero mismatches: {failures:?}"
    );
}

/// The domain and the outside flags on the GPU as the runtime has them (`Domain`,
/// `Domain::outside`'s bits): the grid's ends and g in the first five words, then one flag
/// word per point, over the test points (t = 0.3 … 200 against 0.5 … 128) and suns down to 0.005.
#[test]
fn the_domain_and_the_outside_flags_on_the_gpu_are_the_runtimes() {
    let tables = TransportTables::from_bytes(SHIPPED).unwrap();
    let dom = tables.domain();
    let mut pts = points(4096);
    for (i, p) in pts.iter_mut().enumerate().step_by(5) {
        p.mu_l = 0.005 + 0.2 * (i % 7) as f32 / 7.0;
    }
    // Points that are not in the slab: every coordinate out in turn, NaN and ±∞ included.
    let at = |thickness, mu_l, depth, mu_v, psi_v| SlabPoint {
        depth,
        thickness,
        mu_v,
        psi_v,
        mu_l,
    };
    let (nan, inf) = (f32::NAN, f32::INFINITY);
    let bad = [
        at(nan, 0.5, 1.0, 0.3, 0.1),
        at(inf, 0.5, 1.0, 0.3, 0.1),
        at(-4.0, 0.5, 1.0, 0.3, 0.1),
        at(4.0, 1.5, 1.0, 0.3, 0.1),
        at(4.0, 0.0, 1.0, 0.3, 0.1),
        at(4.0, nan, 1.0, 0.3, 0.1),
        at(4.0, 0.5, 4.5, 0.3, 0.1),
        at(4.0, 0.5, -0.1, 0.3, 0.1),
        at(4.0, 0.5, 1.0, 2.0, 0.1),
        at(4.0, 0.5, 1.0, nan, 0.1),
        at(4.0, 0.5, 1.0, 0.3, inf),
        at(4.0, 0.5, 1.0, 0.3, nan),
    ];
    let within = pts.len();
    pts.extend(bad);
    let flat: Vec<f32> = pts
        .iter()
        .flat_map(|p| [p.thickness, p.mu_l, p.depth, p.mu_v, p.psi_v])
        .collect();
    let kernel = r#"
@group(0) @binding(0) var<uniform> job: vec4<u32>;
@group(0) @binding(1) var<storage, read> points: array<f32>;
@group(0) @binding(2) var<storage, read_write> out: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i == 0u {
        let d = nephele_tables_domain();
        out[0] = bitcast<u32>(d.thickness.x);
        out[1] = bitcast<u32>(d.thickness.y);
        out[2] = bitcast<u32>(d.mu_l.x);
        out[3] = bitcast<u32>(d.mu_l.y);
        out[4] = bitcast<u32>(d.mean_cosine);
    }
    if i >= job.x {
        return;
    }
    let b = 5u * i;
    let at = nephele_slab_point(points[b], points[b + 1u], points[b + 2u], points[b + 3u],
        points[b + 4u]);
    out[5u + i] = nephele_outside(at);
}
"#;
    let source = format!(
        "{}\n{}\n{kernel}",
        nephele_wgsl::PHASE,
        nephele_wgsl::tables(0, 3)
    );
    let ntt = nephele_wgsl::ntt_for_gpu(SHIPPED).unwrap();
    let out = run_kernel(
        &pipeline("domain", &source),
        [pts.len() as u32, 0, 0, 0],
        &flat,
        Some(&ntt),
        4 * (5 + pts.len() as u64),
        pts.len() as u32,
    );
    let words: &[u32] = bytemuck::cast_slice(&out);
    let f = |i: usize| f32::from_bits(words[i]);
    assert_eq!(
        (f(0), f(1), f(2), f(3), f(4)),
        (
            dom.thickness.0,
            dom.thickness.1,
            dom.mu_l.0,
            dom.mu_l.1,
            tables.mean_cosine()
        )
    );
    let mut kinds = [0usize; 8];
    for (i, p) in pts.iter().enumerate().skip(within) {
        assert!(p.check().is_err(), "{p:?}");
        assert_eq!(words[5 + i], 8, "not in the slab: {p:?}");
    }
    for (i, p) in pts.iter().enumerate().take(within) {
        let want = dom.outside(p).bits(&dom);
        assert_eq!(words[5 + i], want, "{p:?}");
        kinds[want as usize] += 1;
    }
    // Every kind was tried: within, thicker, thinner, the sun below, and both.
    for bits in [0, 1, 2, 4, 5, 6] {
        assert!(kinds[bits] > 0, "no point with flags {bits}: {kinds:?}");
    }
}

/// Per point, T, c and σ of every group by `nephele_evaluate_all` (the point's features built
/// once) against eight `nephele_evaluate(g, at)` calls (built for each group), and T alone by
/// `nephele_transport_all` against eight `nephele_transport(g, at)`, in one run on 2·10⁴
/// points, each kernel timed three times in turn (the best kept): a record, not a GPU claim
/// (`cargo test --release -p nephele-wgsl --test tables -- --ignored --nocapture`). With
/// NEPHELE_WGSL_BASELINE=DIR (an earlier version's WGSL sources and tests/tables_kernel.wgsl:
/// scripts/bench_wgsl.sh) that version's kernel is timed too.
#[test]
#[ignore]
fn all_groups_per_call_throughput_record() {
    let tables = TransportTables::from_bytes(SHIPPED).unwrap();
    let groups = tables.groups();
    let pts = points(20_000);
    let flat: Vec<f32> = pts
        .iter()
        .flat_map(|p| [p.thickness, p.mu_l, p.depth, p.mu_v, p.psi_v])
        .collect();
    let ntt = nephele_wgsl::ntt_for_gpu(SHIPPED).unwrap();
    let all = "    let all = nephele_evaluate_all(at);\n    for (var g = 0u; g < job.y; g++) {\n        let e = all[g];";
    assert!(KERNEL.contains(all), "the kernel's loop");
    let src = format!("{}\n{}", nephele_wgsl::PHASE, nephele_wgsl::tables(0, 3));
    let with = |body: &str| format!("{src}\n{}", KERNEL.replace(all, body));
    let mut kernels = vec![
        ("T, c, σ: nephele_evaluate_all", with(all), flat.clone()),
        (
            "T, c, σ: nephele_evaluate per group",
            with("    for (var g = 0u; g < job.y; g++) {\n        let e = nephele_evaluate(g, at);"),
            flat.clone(),
        ),
        (
            "T: nephele_transport_all",
            with("    let all = nephele_transport_all(at);\n    for (var g = 0u; g < job.y; g++) {\n        let e = NepheleTransport(all[g], 0.0, 0.0, 0.0);"),
            flat.clone(),
        ),
        (
            "T: nephele_transport per group",
            with("    for (var g = 0u; g < job.y; g++) {\n        let e = NepheleTransport(nephele_transport(g, at), 0.0, 0.0, 0.0);"),
            flat.clone(),
        ),
    ];
    if let Ok(dir) = std::env::var("NEPHELE_WGSL_BASELINE") {
        let read = |f: &str| std::fs::read_to_string(format!("{dir}/{f}")).expect(f);
        let old = [
            "math.wgsl",
            "phase.wgsl",
            "ntt.wgsl",
            "order1.wgsl",
            "transport.wgsl",
        ]
        .map(read)
        .concat()
            + &read("collector.wgsl");
        let old = old
            .replace("NEPHELE_NTT_GROUP", "0")
            .replace("NEPHELE_NTT_INDEX_BINDING", "4")
            .replace("NEPHELE_NTT_BINDING", "3");
        // Its points in its own field order (depth, thickness, μ_V, ψ_V, μ_L).
        let old_flat = pts
            .iter()
            .flat_map(|p| [p.depth, p.thickness, p.mu_v, p.psi_v, p.mu_l])
            .collect();
        kernels.push((
            "T, c, σ: baseline per group",
            format!("{old}\n{}", read("tables_kernel.wgsl")),
            old_flat,
        ));
    }
    let compiled: Vec<_> = kernels
        .iter()
        .map(|(name, src, data)| (name, pipeline(name, src), data))
        .collect();
    let mut best = vec![f64::INFINITY; compiled.len()];
    for _ in 0..3 {
        for (k, (_, kernel, data)) in compiled.iter().enumerate() {
            let start = Instant::now();
            run_kernel(
                kernel,
                [pts.len() as u32, groups as u32, 0, 0],
                data,
                Some(&ntt),
                4 * (4 * groups as u64 + 1) * pts.len() as u64,
                pts.len() as u32,
            );
            best[k] = best[k].min(start.elapsed().as_secs_f64());
        }
    }
    for ((name, _, _), s) in compiled.iter().zip(&best) {
        println!(
            "{name}: {:.3e} points/s ({groups} groups and order 1)",
            pts.len() as f64 / s
        );
    }
    let ratio = |a: usize, b: usize| best[b] / best[a];
    println!(
        "all groups per call: {:.2}x the per-group calls (T, c, σ), {:.2}x (T)",
        ratio(0, 1),
        ratio(2, 3)
    );
    if best.len() > 4 {
        println!(
            "nephele_evaluate_all: {:.2}x the baseline's per-group calls",
            ratio(0, 4)
        );
    }
}
