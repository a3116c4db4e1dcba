//! Cost of one evaluation of the compressed tables at one point (d, t, μ_V, ψ_V, μ_L), f32, one
//! core: T of every order group; T, c and σ of every group; and order 1. The target is
//! ≤ 1 µs for all groups.
//!
//!     cargo run --release --example bench_transport -- outputs/transport/mie10um/transport.ntt

use nephele_runtime::transport::tables::{Transport, TransportTables};
use std::hint::black_box;
use std::time::Instant;

fn main() {
    let path = std::env::args()
        .nth(1)
        .expect("usage: bench_transport FILE.ntt");
    let bytes = std::fs::read(&path).expect("read the tables");
    let tab = TransportTables::from_bytes(&bytes).expect("valid tables");
    // A fixed pseudo-random set of points inside the slab.
    let mut x: u32 = 12345;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        x as f32 / u32::MAX as f32
    };
    let points: Vec<[f32; 5]> = (0..4096)
        .map(|_| {
            let t = 0.5 * 256f32.powf(next());
            [
                next() * t,
                t,
                2.0 * next() - 1.0,
                std::f32::consts::PI * next(),
                0.1 + 0.9 * next(),
            ]
        })
        .collect();
    for &[d, t, mu_v, psi, mu_l] in &points {
        let v = tab.order1(d, t, mu_v, psi, mu_l);
        assert!(
            v.is_finite() && v >= 0.0,
            "order 1 = {v} at d {d} t {t} mu_v {mu_v} psi {psi} mu_l {mu_l}"
        );
    }
    let rounds = 50;
    let time = |name: &str, f: &mut dyn FnMut(&[f32; 5]) -> f32| {
        let t0 = Instant::now();
        let mut sum = 0.0f32;
        for _ in 0..rounds {
            for p in &points {
                sum += f(p);
            }
        }
        let ns = t0.elapsed().as_nanos() as f64 / (rounds * points.len()) as f64;
        println!(
            "{name}: {ns:.0} ns per point ({} groups) [{}]",
            tab.groups(),
            black_box(sum).is_finite()
        );
    };
    time(
        "T of all groups of orders ≥ 2",
        &mut |&[d, t, mu_v, psi, mu_l]| {
            let mut all = [0.0f32; 16];
            tab.transport_all(d, t, mu_v, psi, mu_l, &mut all);
            all.iter().sum()
        },
    );
    time("T, c, σ of all groups", &mut |&[d, t, mu_v, psi, mu_l]| {
        let mut all = [Transport::default(); 16];
        tab.evaluate_all(d, t, mu_v, psi, mu_l, &mut all);
        all.iter().map(|v| v.t + v.c_z + v.sigma).sum()
    });
    time("order 1", &mut |&[d, t, mu_v, psi, mu_l]| {
        tab.order1(d, t, mu_v, psi, mu_l)
    });
}
