//! The WGSL phase models run on a real Vulkan driver (Mesa's lavapipe on the CPU in CI: `apt-get
//! install mesa-vulkan-drivers`; any Vulkan, Metal or DX12 GPU elsewhere) and compared with the
//! Rust runtime: eval on 10⁵ cosines over the whole sphere (the forward peak down to 1 − μ =
//! 1e-8, both poles), HG + Draine's parameters from the droplet diameter, and sampling — the
//! CDF of every GPU sample against its ξ, and the runtime's chi-square test (Mitsuba's
//! `chi2.py` style, `nephele_stats::chi2`) on the GPU's samples.
//!
//! `cargo test --release -p nephele-wgsl -- --nocapture` prints the agreement per model.

use nephele_runtime::phase::{Cosine, Draine, HenyeyGreenstein, HgDraine, TabulatedTable};
use nephele_runtime::presets::jendersie_deon;
use nephele_runtime::PhaseFunction;
use nephele_stats::chi2::{chi2_sphere, Chi2Config};
use std::sync::OnceLock;

/// The test kernel around the port: one dispatch evaluates (mode 0: inputs are (μ, 1 − μ)),
/// samples (mode 1: inputs are (ξ, ·)) or gives HG + Draine's parameters (mode 2: inputs are
/// (d, ·)) for one model: 0 HG(g), 1 Draine(g, α), 2 HG + Draine(g_HG, g_D, α, w_D),
/// 3 HG + Draine of diameter p.x.
const KERNEL: &str = include_str!("kernel.wgsl");

mod common;
use common::{dispatch, gpu, pipeline, Input};

/// The kernel's pipeline, made once for every test of this file.
fn kernel() -> &'static wgpu::ComputePipeline {
    static PIPELINE: OnceLock<wgpu::ComputePipeline> = OnceLock::new();
    PIPELINE.get_or_init(|| {
        let source = format!(
            "{}\n{}\n{}",
            nephele_wgsl::PHASE,
            nephele_wgsl::tabulated(0, 3),
            KERNEL
        );
        pipeline("phase.wgsl + test kernel", &source)
    })
}

/// Runs the kernel in `mode` for `model` with parameters `p` on `inputs` (the tabulated model
/// reads [`table`]'s buffer).
fn run(mode: u32, model: u32, p: [f32; 4], inputs: &[[f32; 2]]) -> Vec<[f32; 4]> {
    let n = inputs.len() as u32;
    let mut job = [0u8; 32];
    for (k, v) in [mode, model, n, 0].iter().enumerate() {
        job[4 * k..4 * k + 4].copy_from_slice(&v.to_le_bytes());
    }
    for (k, v) in p.iter().enumerate() {
        job[16 + 4 * k..20 + 4 * k].copy_from_slice(&v.to_le_bytes());
    }
    let tab = nephele_wgsl::tabulated_buffer(&table().view());
    let out = dispatch(
        kernel(),
        &[
            Input {
                binding: 0,
                bytes: &job,
                uniform: true,
            },
            Input {
                binding: 1,
                bytes: bytemuck::cast_slice(inputs),
                uniform: false,
            },
            Input {
                binding: 3,
                bytes: bytemuck::cast_slice(&tab),
                uniform: false,
            },
        ],
        (2, 16 * inputs.len() as u64),
        n,
    );
    bytemuck::cast_slice::<u8, [f32; 4]>(&out).to_vec()
}

/// The tabulated model's table: HG + Draine of 10 µm droplets tabulated as a Mie table would be
/// (0.01° steps to 5° through the forward peak, 0.25° beyond: 1 100 nodes).
fn table() -> &'static TabulatedTable<f32> {
    static TABLE: OnceLock<TabulatedTable<f32>> = OnceLock::new();
    TABLE.get_or_init(table_of::<f32>)
}

fn table_of<F: nephele_runtime::Real>() -> TabulatedTable<F> {
    let deg: Vec<f64> = (0..500)
        .map(|i| i as f64 * 0.01)
        .chain((0..=700).map(|i| 5.0 + i as f64 * 0.25))
        .collect();
    let blend = HgDraine::<f64>::from_diameter(10.0);
    let p: Vec<f64> = deg
        .iter()
        .map(|d| blend.eval(d.to_radians().cos()))
        .collect();
    TabulatedTable::from_phase(&deg, &p).expect("a valid table")
}

/// A model as the kernel takes it, and the runtime's f32 and f64 versions.
struct Case {
    name: String,
    model: u32,
    p: [f32; 4],
    f32: Box<dyn PhaseFunction<f32> + Sync>,
    f64: Box<dyn PhaseFunction<f64> + Sync>,
    /// How far the CDF of a sample μ (f64) lies from the ξ it was drawn with, beyond what one
    /// f32 ulp of μ spans there: for a mixture, the CDF of the lobe ξ picked, at ξ rescaled to
    /// it; for the tabulated model (whose f64 CDF the runtime does not expose), the probability
    /// between the GPU's μ and the runtime's f32 sample of the same ξ, beyond 4 ulps.
    cdf_error: Box<dyn Fn(f32, f32) -> f64 + Sync>,
}

/// |F(μ) − ξ| of a lobe of CDF `cdf` and pdf `pdf`, less the CDF one f32 ulp of μ spans.
fn cdf_error(cdf: impl Fn(f64) -> f64, pdf: impl Fn(f64) -> f64, xi: f64, mu: f32) -> f64 {
    let ulp = (f32::from_bits(mu.abs().to_bits() + 1) - mu.abs()) as f64;
    let limit = 2.0 * std::f64::consts::PI * pdf(mu as f64) * ulp;
    ((cdf(mu as f64) - xi).abs() - limit).max(0.0)
}

fn cases() -> Vec<Case> {
    let mut v = Vec::new();
    for g in [-0.7f32, 1e-6, 0.3, 0.85, 0.99] {
        v.push(Case {
            name: format!("HG g={g}"),
            model: 0,
            p: [g, 0.0, 0.0, 0.0],
            f32: Box::new(HenyeyGreenstein::new(g)),
            f64: Box::new(HenyeyGreenstein::new(g as f64)),
            cdf_error: Box::new(move |xi, mu| {
                let hg = HenyeyGreenstein::new(g as f64);
                cdf_error(|m| hg.cdf(m), |m| hg.eval(m), xi as f64, mu)
            }),
        });
    }
    for (g, a) in [(0.5f32, 250.0f32), (0.9, 1.0), (-0.3, 10.0), (1e-6, 250.0)] {
        let d64 = Draine::new(g as f64, a as f64);
        v.push(Case {
            name: format!("Draine g={g} a={a}"),
            model: 1,
            p: [g, a, 0.0, 0.0],
            f32: Box::new(Draine::new(g, a)),
            f64: Box::new(d64),
            cdf_error: Box::new(move |xi, mu| {
                cdf_error(|m| d64.cdf(m), |m| d64.eval(m), xi as f64, mu)
            }),
        });
    }
    {
        let t64: &'static TabulatedTable<f64> = Box::leak(Box::new(table_of::<f64>()));
        let v64 = t64.view();
        v.push(Case {
            name: "tabulated (d=10 table)".into(),
            model: 4,
            p: [0.0; 4],
            f32: Box::new(table().view()),
            f64: Box::new(v64),
            // The runtime's own f32 sampler on the same ξ: the GPU's sample against it.
            cdf_error: Box::new(move |xi, mu| {
                let want = table().view().sample_cosine(xi);
                let step = (mu - want.mu).abs() as f64;
                let ulp = (f32::from_bits(want.mu.abs().to_bits() + 1) - want.mu.abs()) as f64;
                let density = 2.0 * std::f64::consts::PI * v64.eval(want.mu as f64);
                (step - 4.0 * ulp).max(0.0) * density
            }),
        });
    }
    for d in [0.05f32, 0.5, 2.0, 10.0, 40.0] {
        // The runtime's parameters rounded to f32, as the kernel receives them.
        let q = jendersie_deon(d as f64);
        let p = [q.g_hg as f32, q.g_d as f32, q.alpha as f32, q.w_d as f32];
        let m64 = HgDraine::hg_draine(p[0] as f64, p[1] as f64, p[2] as f64, p[3] as f64);
        let (hg, dr) = (m64.first, m64.second);
        let w = 1.0 - p[3];
        v.push(Case {
            name: format!("HG+Draine d={d}"),
            model: 2,
            p,
            f32: Box::new(HgDraine::hg_draine(p[0], p[1], p[2], p[3])),
            f64: Box::new(m64),
            // The lobe ξ picks, at ξ rescaled to it as the kernel does (in f32).
            cdf_error: Box::new(move |xi, mu| {
                if xi < w {
                    cdf_error(|m| hg.cdf(m), |m| hg.eval(m), (xi / w) as f64, mu)
                } else {
                    let x = ((xi - w) / (1.0 - w)).clamp(0.0, 1.0) as f64;
                    cdf_error(|m| dr.cdf(m), |m| dr.eval(m), x, mu)
                }
            }),
        });
    }
    v
}

/// 10⁵ / models cosines per model: uniform in μ, log-uniform in 1 − μ from 1e-8 (the peak),
/// and the poles, as (μ, 1 − μ).
fn cosines(n: usize) -> Vec<[f32; 2]> {
    let mut rng = nephele_stats::XorShift64::new(0x9E37_79B9_7F4A_7C15);
    let mut r = || f64::from(rng.unit_f32());
    let mut v = vec![[1.0, 0.0], [-1.0, 2.0], [0.0, 1.0]];
    while v.len() < n {
        if v.len() % 2 == 0 {
            let mu = (2.0 * r() - 1.0) as f32;
            v.push([mu, 1.0 - mu]);
        } else {
            let omm = 10f64.powf(-8.0 + 8.3 * r()).min(2.0);
            v.push([(1.0 - omm) as f32, omm as f32]);
        }
    }
    v
}

#[test]
fn phase_models_evaluate_as_the_runtime() {
    let cases = cases();
    let n = 100_000 / cases.len() + 1;
    let at = cosines(n);
    println!("adapter: {}", gpu().adapter);
    let mut failures = Vec::new();
    for c in &cases {
        let out = run(0, c.model, c.p, &at);
        let want: Vec<f32> = at
            .iter()
            .map(|x| {
                c.f32.pdf_cosine(Cosine {
                    mu: x[0],
                    one_minus_mu: x[1],
                })
            })
            .collect();
        let top = want.iter().fold(0.0f32, |a, &b| a.max(b));
        let (mut worst, mut at_worst) = (0.0f64, [0.0f32; 2]);
        for ((x, o), w) in at.iter().zip(&out).zip(&want) {
            if *w > 1e-6 * top {
                let rel = ((o[0] - w) / w).abs() as f64;
                if !(rel <= worst) {
                    (worst, at_worst) = (rel, *x);
                }
            }
        }
        println!(
            "{:<22} eval: largest relative difference {worst:.2e} (μ = {}, 1 − μ = {:.1e})",
            c.name, at_worst[0], at_worst[1]
        );
        if !(worst <= 1e-5) {
            failures.push(format!("{}: {worst:.2e}", c.name));
        }
    }
    assert!(failures.is_empty(), "beyond 1e-5: {failures:?}");
}

#[test]
fn hg_draine_by_diameter_follows_the_runtime() {
    let ds: Vec<[f32; 2]> = (0..10_000)
        .map(|i| [(0.02 * 2500f64.powf(i as f64 / 9999.0)) as f32, 0.0])
        .collect();
    let out = run(2, 0, [0.0; 4], &ds);
    // Compared through what the parameters are for: the phase function at 64 cosines from the
    // backward pole to the forward peak, GPU parameters against the runtime's.
    let mut worst = (0.0f64, 0.0f32);
    for (d, o) in ds.iter().zip(&out) {
        let q = jendersie_deon(d[0] as f64);
        let want = HgDraine::hg_draine(q.g_hg, q.g_d, q.alpha, q.w_d);
        let got = HgDraine::hg_draine(o[0] as f64, o[1] as f64, o[2] as f64, o[3] as f64);
        for k in 0..64 {
            let omm = 2.0 * 1e-6f64.powf(k as f64 / 63.0);
            let c = Cosine {
                mu: 1.0 - omm,
                one_minus_mu: omm,
            };
            let rel = (got.pdf_cosine(c) / want.pdf_cosine(c) - 1.0).abs();
            if !(rel <= worst.0) {
                worst = (rel, d[0]);
            }
        }
    }
    println!(
        "HG+Draine by diameter (0.02–50 µm, 10⁴ diameters): phase function from the GPU's \
         parameters within {:.2e} of the runtime's (worst at d = {} µm)",
        worst.0, worst.1
    );
    // f32 parameters: g within an ulp or two of 0.99 moves the forward peak by ~2e-5.
    assert!(worst.0 <= 1e-4, "{worst:?}");
}

#[test]
fn gpu_samples_invert_the_cdf_and_pass_chi_square() {
    let cases = cases();
    let cfg = Chi2Config {
        samples: 100_000,
        seed: 7,
        ..Chi2Config::default()
    };
    let mut failures = Vec::new();
    for c in &cases {
        // The ξ pairs chi2_sphere draws, recorded, then sampled on the GPU in one dispatch.
        let xis = std::sync::Mutex::new(Vec::with_capacity(cfg.samples));
        chi2_sphere(
            &cfg,
            |a, b| {
                xis.lock().unwrap().push((a, b));
                [0.0, 0.0, 1.0]
            },
            |_| 1.0,
        );
        let xis = xis.into_inner().unwrap();
        let inputs: Vec<[f32; 2]> = xis.iter().map(|&(a, _)| [a as f32, 0.0]).collect();
        let out = run(1, c.model, c.p, &inputs);
        // CDF of each sample against its ξ, beyond what one f32 ulp of μ spans there.
        let cdf_err = inputs
            .iter()
            .zip(&out)
            .map(|(x, o)| (c.cdf_error)(x[0], o[0]))
            .fold(0.0f64, f64::max);
        let next = std::sync::atomic::AtomicUsize::new(0);
        let result = chi2_sphere(
            &cfg,
            |_, b| {
                let o = out[next.fetch_add(1, std::sync::atomic::Ordering::Relaxed)];
                let (mu, sin) = (
                    o[0] as f64,
                    (o[1] as f64 * (2.0 - o[1] as f64)).max(0.0).sqrt(),
                );
                let phi = 2.0 * std::f64::consts::PI * b;
                [sin * phi.cos(), sin * phi.sin(), mu]
            },
            |d| c.f64.eval(d[2]),
        );
        println!(
            "{:<22} sample: CDF within {cdf_err:.1e} of ξ, chi-square p = {:.3} ({} dof)",
            c.name, result.p_value, result.dof
        );
        if !result.passes(0.01, cases.len()) || !(cdf_err <= 1e-5) {
            failures.push(format!(
                "{}: p = {:.2e}, CDF error {cdf_err:.1e}",
                c.name, result.p_value
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}

/// A record, not a claim about GPUs: HG + Draine (d = 10 µm) samples per second on this
/// adapter (10⁶ per dispatch, upload and read-back included, best of 3) beside the runtime's
/// f32 sampler on one CPU core, in the same run.
#[test]
fn sampling_throughput_record() {
    let n = 1_000_000;
    let xis: Vec<[f32; 2]> = (0..n)
        .map(|i| [((i as f64 + 0.5) / n as f64) as f32, 0.0])
        .collect();
    let best = |f: &mut dyn FnMut()| {
        (0..3)
            .map(|_| {
                let t = std::time::Instant::now();
                f();
                t.elapsed().as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min)
    };
    let gpu_s = best(&mut || {
        std::hint::black_box(run(1, 3, [10.0, 0.0, 0.0, 0.0], &xis));
    });
    let phase = HgDraine::<f32>::from_diameter(10.0);
    let cpu_s = best(&mut || {
        let s: f32 = xis.iter().map(|x| phase.sample_mu(x[0])).sum();
        std::hint::black_box(s);
    });
    println!(
        "HG+Draine d=10 sampling: {:.2e} samples/s on {} (dispatch and read-back included), \
         {:.2e} samples/s for the runtime on one CPU core",
        n as f64 / gpu_s,
        gpu().adapter,
        n as f64 / cpu_s
    );
}
