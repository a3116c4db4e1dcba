//! Cost of one evaluation of the compressed tables at one point (d, t, μ_V, ψ_V, μ_L), f32, one
//! core: T of every order group; T of one group; T, c and σ of every group and of one; and
//! order 1. The target is ≤ 1.5 µs for T of all groups.
//!
//!     cargo run --release --example bench_transport -- runtime/tables/mie10um/transport.ntt

use nephele_runtime::transport::{SlabPoint, Transport, TransportTables};
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
    let points: Vec<SlabPoint<f32>> = (0..4096)
        .map(|_| {
            let t = 0.5 * 256f32.powf(next());
            SlabPoint {
                depth: next() * t,
                thickness: t,
                mu_v: 2.0 * next() - 1.0,
                psi_v: std::f32::consts::PI * next(),
                mu_l: 0.1 + 0.9 * next(),
            }
        })
        .collect();
    for p in &points {
        let v = tab.order1(p);
        assert!(v.is_finite() && v >= 0.0, "order 1 = {v} at {p:?}");
    }
    let rounds = 50;
    let time = |name: &str, f: &mut dyn FnMut(&SlabPoint<f32>) -> f32| {
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
    time("T of all groups of orders ≥ 2", &mut |p| {
        let mut all = [0.0f32; 16];
        tab.transport_all(p, &mut all);
        all.iter().sum()
    });
    time("T of one group (the fourth)", &mut |p| tab.transport(3, p));
    time("T, c, σ of all groups", &mut |p| {
        let mut all = [Transport::default(); 16];
        tab.evaluate_all(p, &mut all);
        all.iter().map(|v| v.t + v.c_z + v.sigma).sum()
    });
    time("T, c, σ of one group (the fourth)", &mut |p| {
        let v = tab.evaluate(3, p);
        v.t + v.c_z + v.sigma
    });
    time("order 1", &mut |p| tab.order1(p));
}
