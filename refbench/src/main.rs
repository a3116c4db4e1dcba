//! nephele against the C baselines of benches/baselines/ in one process, alternately: the
//! ratios on a machine whose clock drifts.
//!
//!     cargo run --release -p nephele-refbench -- phase [CALLS [ROUNDS]]
//!     cargo run --release -p nephele-refbench -- slab [PHOTONS [ROUNDS]]
//!
//! The baselines are compiled as their headers say (`cc -O3 -march=native`, build.rs), their
//! sources unchanged. Each round runs a C loop and nephele's same loop one right after the
//! other, the order swapped every round, and takes the ratio of the two: milliseconds apart,
//! both see the same clock. Printed per comparison: the median ratio over the rounds with its
//! quartiles and range, and the medians of each side's own figure.
//!
//! - `phase`: ns per call, nephele / C, of the f32 loops of phase_ref.c's main (xorshift
//!   numbers converted as there, an accumulated sum; c/phase.c has each loop as a function of
//!   its own), the models called directly as the C forms are: HG evaluated and sampled, the
//!   HG + Draine blend of d = 20 µm evaluated and sampled, its Draine lobe sampled. nephele
//!   samples exactly (1 − μ too); the C forms do not.
//! - `slab`: scattering events per second, nephele / C, of the walk on slab_ref.c's problem
//!   (τ = 4, HG g = 0.9, normal incidence): slab_ref.c's own main (its output captured by
//!   c/capture.c, its events read from it), which tallies totals and 10 μ bins, against
//!   nephele's walk with every table's tallies (examples/bench_slab.rs).

use nephele::slab::walk::batch_rng;
use nephele::slab::{SlabGrid, Slice};
use nephele_runtime::fitting::Simd;
use nephele_runtime::phase::{Draine, HenyeyGreenstein};
use nephele_runtime::presets::jendersie_deon;
use nephele_runtime::PhaseFunction;
use std::ffi::{c_char, c_int, c_long, CStr, CString};
use std::hint::black_box;
use std::process::ExitCode;
use std::time::Instant;

extern "C" {
    fn ref_hg_eval(n: c_long) -> f64;
    fn ref_hg_sample(n: c_long) -> f64;
    fn ref_draine_sample(n: c_long) -> f64;
    fn ref_blend_eval(n: c_long) -> f64;
    fn ref_blend_sample(n: c_long) -> f64;
    fn slab_ref_main(argc: c_int, argv: *const *const c_char) -> c_int;
    fn ref_output() -> *const c_char;
    fn ref_clear();
}

/// Runs slab_ref.c's `main` with `args` and returns what it printed.
fn run_slab_ref(args: &[&str]) -> String {
    let owned: Vec<CString> = args
        .iter()
        .map(|a| CString::new(*a).expect("no NUL"))
        .collect();
    let argv: Vec<*const c_char> = owned.iter().map(|a| a.as_ptr()).collect();
    // SAFETY: argv holds argc valid C strings that outlive the call; the baseline reads its
    // arguments and prints into the capture buffer (bounded), nothing else.
    unsafe {
        ref_clear();
        slab_ref_main(argv.len() as c_int, argv.as_ptr());
        CStr::from_ptr(ref_output()).to_string_lossy().into_owned()
    }
}

/// The number after `key` in `text` (e.g. "events=" → 2879623).
fn number_after(text: &str, key: &str) -> f64 {
    let at = text
        .find(key)
        .unwrap_or_else(|| panic!("the baseline printed no {key:?}:\n{text}"));
    text[at + key.len()..]
        .trim_start()
        .split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == 'e'))
        .next()
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no number after {key:?}:\n{text}"))
}

/// phase_ref.c's generator: xorshift64, the top 24 bits as a float in [0, 1).
struct Xorshift(u64);

impl Xorshift {
    #[inline(always)]
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 * (1.0 / 16_777_216.0)
    }
}

/// ns per call of `op` in phase_ref.c's loop: the sum of n results.
#[inline(always)]
fn ns_per_call(n: usize, rng: &mut Xorshift, mut op: impl FnMut(&mut Xorshift) -> f32) -> f64 {
    let t0 = Instant::now();
    let mut acc = 0.0f32;
    for _ in 0..n {
        acc += op(rng);
    }
    black_box(acc);
    t0.elapsed().as_secs_f64() / n as f64 * 1e9
}

/// One comparison: its name, the C loop, and nephele's loop (ns per call each).
type PhaseCase = (
    &'static str,
    unsafe extern "C" fn(c_long) -> f64,
    fn(usize, &mut Xorshift) -> f64,
);

fn phase_cases() -> Vec<PhaseCase> {
    vec![
        ("HG eval", ref_hg_eval, |n, r| {
            let hg = HenyeyGreenstein::new(0.85f32);
            ns_per_call(n, r, |r| hg.eval(2.0 * r.next() - 1.0))
        }),
        ("HG sample (exact 1 − μ)", ref_hg_sample, |n, r| {
            let hg = HenyeyGreenstein::new(0.85f32);
            ns_per_call(n, r, |r| hg.sample_mu(r.next()))
        }),
        ("HG+Draine eval", ref_blend_eval, |n, r| {
            let blend = jendersie_deon(20.0).phase::<f32>();
            ns_per_call(n, r, |r| blend.eval(2.0 * r.next() - 1.0))
        }),
        ("HG+Draine sample (exact)", ref_blend_sample, |n, r| {
            let blend = jendersie_deon(20.0).phase::<f32>();
            ns_per_call(n, r, |r| blend.sample_mu(r.next()))
        }),
        ("Draine sample, lobe (exact)", ref_draine_sample, |n, r| {
            let b = jendersie_deon(20.0);
            let draine = Draine::new(b.g_d as f32, b.alpha as f32);
            ns_per_call(n, r, |r| draine.sample_mu(r.next()))
        }),
    ]
}

/// Median, quartiles and range of `v`.
fn summary(v: &mut [f64]) -> (f64, f64, f64, f64, f64) {
    v.sort_by(f64::total_cmp);
    let at = |q: f64| {
        let x = q * (v.len() - 1) as f64;
        let (i, f) = (x.floor() as usize, x.fract());
        v[i] + f * (v[(i + 1).min(v.len() - 1)] - v[i])
    };
    (at(0.5), at(0.25), at(0.75), v[0], v[v.len() - 1])
}

/// Prints one comparison's line: ratios nephele / C and each side's median.
fn report(name: &str, ratios: &mut [f64], ours: &mut [f64], theirs: &mut [f64], unit: &str) {
    let (m, q1, q3, lo, hi) = summary(ratios);
    println!(
        "   {name:<30} {m:.3} (quartiles {q1:.3}–{q3:.3}, range {lo:.3}–{hi:.3}); medians: nephele {:.2}, C {:.2} {unit}",
        summary(ours).0,
        summary(theirs).0
    );
}

fn phase(calls: usize, rounds: usize) {
    let cases = phase_cases();
    let mut rng = Xorshift(0x853c49e6748fea9b);
    let (mut ours, mut theirs) = (vec![vec![]; cases.len()], vec![vec![]; cases.len()]);
    for round in 0..rounds {
        for (k, &(_, c_loop, our_loop)) in cases.iter().enumerate() {
            // SAFETY: the C loop reads and writes only its own statics.
            let mut run_c = || theirs[k].push(unsafe { c_loop(calls as c_long) });
            if round % 2 == 0 {
                run_c();
                ours[k].push(our_loop(calls, &mut rng));
            } else {
                ours[k].push(our_loop(calls, &mut rng));
                run_c();
            }
        }
    }
    println!(
        "   nephele / C, ns per call (target ≤ 1.0 for evaluation and the blend's and Draine's \
         sampling), {rounds} rounds of {calls} calls:"
    );
    for (k, (name, _, _)) in cases.iter().enumerate() {
        let mut ratios: Vec<f64> = ours[k].iter().zip(&theirs[k]).map(|(a, b)| a / b).collect();
        report(name, &mut ratios, &mut ours[k], &mut theirs[k], "ns");
    }
}

fn slab(photons: u64, rounds: usize) {
    let hg = HenyeyGreenstein::new(0.9);
    let grid = SlabGrid::default_with_annuli(4.0).expect("the default grid and annuli");
    let slice = Slice {
        grid: &grid,
        mu_l: 1.0,
        albedo: 1.0,
        phase: &hg,
    };
    let n = photons.to_string();
    let (mut ours, mut theirs) = (vec![], vec![]);
    for round in 0..rounds {
        let run_c = || {
            let t0 = Instant::now();
            let out = run_slab_ref(&["slab_ref", "4", "0.9", &n]);
            number_after(&out, "events=") / t0.elapsed().as_secs_f64() / 1e6
        };
        let run_ours = || {
            let t0 = Instant::now();
            let tally = slice.run_batch(photons, &mut batch_rng(1, round as u64, 0));
            tally.events as f64 / t0.elapsed().as_secs_f64() / 1e6
        };
        if round % 2 == 0 {
            theirs.push(run_c());
            ours.push(run_ours());
        } else {
            ours.push(run_ours());
            theirs.push(run_c());
        }
    }
    println!(
        "   nephele / C walk, scattering events per second (target ≥ 1.0), {rounds} rounds of {photons} photons:"
    );
    let mut ratios: Vec<f64> = ours.iter().zip(&theirs).map(|(a, b)| a / b).collect();
    report(
        "events/s, μ_L = 1",
        &mut ratios,
        &mut ours,
        &mut theirs,
        "M events/s",
    );
}

/// The CPU's model (Linux) and the SIMD level nephele's run-time dispatch reaches on it.
fn cpu() -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|info| {
            info.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into());
    let level = Simd::detected().name();
    format!("CPU: {model}; nephele's dispatch: {level}; the C baselines: -march=native")
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    // The count (calls or photons) and the rounds, each a positive integer or its default.
    let number = |i: usize, default: u64| -> Option<u64> {
        args.get(i)
            .map_or(Some(default), |s| s.parse().ok().filter(|&v| v > 0))
    };
    match args.first().map(String::as_str) {
        Some("phase") => {
            if let (Some(calls), Some(rounds)) = (number(1, 10_000_000), number(2, 30)) {
                println!("   {}", cpu());
                phase(calls as usize, rounds as usize);
                return ExitCode::SUCCESS;
            }
        }
        Some("slab") => {
            if let (Some(photons), Some(rounds)) = (number(1, 500_000), number(2, 40)) {
                println!("   {}", cpu());
                slab(photons, rounds as usize);
                return ExitCode::SUCCESS;
            }
        }
        _ => {}
    }
    eprintln!(
        "usage: nephele-refbench phase [CALLS [ROUNDS]] | slab [PHOTONS [ROUNDS]]\n\
         (positive integers; defaults: 10000000 calls and 30 rounds, 500000 photons and 40 rounds)"
    );
    ExitCode::FAILURE
}
