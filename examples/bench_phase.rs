//! ns per evaluation and per sample of the runtime's phase models, f32 and f64, in the same
//! loop shape as benches/baselines/phase_ref.c (xorshift numbers, an accumulated sum), so that
//! scripts/bench_phase.sh can print both side by side.
//!
//!     cargo run --release --example bench_phase [-- N]

use nephele_runtime::phase::{
    Draine, HenyeyGreenstein, Rayleigh, Schlick, TabulatedTable, TwoTermHg, VonMisesFisher,
};
use nephele_runtime::presets::jendersie_deon;
use nephele_runtime::{PhaseFunction, Real};
use nephele_stats::XorShift64;
use std::hint::black_box;
use std::time::Instant;

struct Rng(XorShift64);
impl Rng {
    #[inline]
    fn next<F: Real>(&mut self) -> F {
        F::of(f64::from(self.0.unit_f32()))
    }
}

fn time<F: Real>(name: &str, n: usize, mut op: impl FnMut(&mut Rng) -> F) {
    let mut rng = Rng(XorShift64::new(0x853c49e6748fea9b));
    let t0 = Instant::now();
    let mut acc = F::of(0.0);
    for _ in 0..n {
        acc = acc + op(&mut rng);
    }
    black_box(acc);
    println!(
        "{name:<34} {:6.2} ns",
        t0.elapsed().as_secs_f64() / n as f64 * 1e9
    );
}

fn models<F: Real + 'static>(n: usize, prec: &str) {
    let b = jendersie_deon(20.0);
    let blend = b.phase::<F>();
    let hg = HenyeyGreenstein::new(F::of(0.85));
    let draine = Draine::new(F::of(b.g_d), F::of(b.alpha));
    let cases: Vec<(&str, Box<dyn PhaseFunction<F>>)> = vec![
        ("hg", Box::new(hg)),
        ("draine (d = 20 µm lobe)", Box::new(draine)),
        (
            "draine g=0.02 α=250",
            Box::new(Draine::new(F::of(0.02), F::of(250.0))),
        ),
        ("hg+draine (d = 20 µm)", Box::new(blend)),
        ("rayleigh", Box::new(Rayleigh)),
        ("schlick", Box::new(Schlick::new(F::of(0.8)))),
        ("vmf", Box::new(VonMisesFisher::new(F::of(20.0)))),
        (
            "two-term hg",
            Box::new(TwoTermHg::two_term(F::of(0.9), F::of(-0.3), F::of(0.8))),
        ),
    ];
    for (name, p) in &cases {
        time::<F>(&format!("{prec} {name} eval"), n, |r| {
            p.eval(F::of(2.0) * r.next::<F>() - F::of(1.0))
        });
        time::<F>(&format!("{prec} {name} sample"), n, |r| {
            p.sample_mu(r.next::<F>())
        });
    }
}

/// The same loops with the concrete type known (static dispatch, as a renderer would call).
fn static_dispatch<P: PhaseFunction<f32>>(name: &str, p: &P, n: usize) {
    time::<f32>(&format!("f32 {name} eval (static)"), n, |r| {
        p.eval(2.0 * r.next::<f32>() - 1.0)
    });
    time::<f32>(&format!("f32 {name} sample (static)"), n, |r| {
        p.sample_mu(r.next::<f32>())
    });
}

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .map_or(10_000_000, |s| s.parse().unwrap());
    static_dispatch("hg", &HenyeyGreenstein::new(0.85f32), n);
    static_dispatch(
        "hg+draine (d = 20 µm)",
        &jendersie_deon(20.0).phase::<f32>(),
        n,
    );
    models::<f32>(n, "f32");
    models::<f64>(n, "f64");
    // The 50 µm Mie table of stage 1 (product rule 41 × 16: the peak is what matters here).
    let job = nephele::mie::MieJob::paper(50.0, nephele::mie::SizeRule::Product { sizes: 41 }, 16);
    let mie = job.compute(&|_, _| {}).unwrap().0.remove(0);
    let (theta, phase) = (mie.theta_deg, mie.phase);
    let tab = TabulatedTable::<f32>::from_phase(&theta, &phase).unwrap();
    let view = tab.view();
    time::<f32>("f32 tabulated 50 µm Mie sample", n, |r| {
        view.sample_mu(r.next::<f32>())
    });
    time::<f32>("f32 tabulated 50 µm Mie eval", n, |r| {
        view.eval(2.0 * r.next::<f32>() - 1.0)
    });
    time::<f32>("(rng alone)", n, |r| r.next::<f32>());
}
