//! Scattering events per second on one core of the slab walk with full tallies (default grid:
//! 16 planes × 16 μ_V × 12 ψ_V × 9 order groups, collector moments, and the 9 aureole annuli
//! around the beam that every table made from a config tallies), on the problem of
//! benches/baselines/slab_ref.c (τ = 4, HG g = 0.9, normal incidence), so that
//! scripts/bench_slab.sh can print both side by side.
//!
//!     cargo run --release --example bench_slab [-- PHOTONS [MU_L [PHASE]]]
//!
//! PHASE is `hg` (HG g = 0.9, the problem of slab_ref.c; the default) or `mie10` (the Mie table
//! of 10 µm droplets the default tables walk with, sampled exactly).

use nephele::phase::{Phase, PhaseSpec};
use nephele::slab::walk::batch_rng;
use nephele::slab::{SlabGrid, Slice};
use nephele_runtime::phase::HenyeyGreenstein;
use nephele_runtime::PhaseFunction;
use std::time::Instant;

fn main() {
    let photons: u64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(2_000_000);
    // Normal incidence by default (the problem of slab_ref.c); a second argument sets μ_L.
    let mu_l: f64 = std::env::args()
        .nth(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1.0);
    let mie = match std::env::args().nth(3).as_deref() {
        None | Some("hg") => None,
        Some("mie10") => Some(
            Phase::build(&PhaseSpec::Mie {
                diameter_um: 10.0,
                rgb: false,
            })
            .expect("the Mie table of 10 µm"),
        ),
        Some(other) => panic!("phase {other}: expected hg or mie10"),
    };
    let hg = HenyeyGreenstein::new(0.9);
    let grid = SlabGrid::default_with_annuli(4.0).expect("the default grid and annuli");
    let walk = |phase: &(dyn PhaseFunction<f64> + Sync)| {
        let slice = Slice {
            grid: &grid,
            mu_l,
            albedo: 1.0,
            phase,
        };
        let t0 = Instant::now();
        let tally = slice.run_batch(photons, &mut batch_rng(1, 0, 0));
        (tally, t0.elapsed().as_secs_f64())
    };
    let (tally, s) = match &mie {
        Some(phase) => phase.with(walk),
        None => walk(&hg),
    };
    let n = photons as f64;
    println!(
        "tau=4 {} mu_L={mu_l} N={photons}  R={:.6} T_diffuse={:.6} T_direct={:.6}",
        if mie.is_some() { "Mie 10 µm" } else { "g=0.9" },
        tally.escaped_top / n,
        tally.down[grid.depths.len() - 1] / n,
        tally.direct[grid.depths.len() - 1] / n
    );
    println!(
        "events={}  events/photon={:.2}  time={s:.2}s  => {:.1} M events/s/core, {:.2} M photons/s/core (full tallies)",
        tally.events,
        tally.events as f64 / n,
        tally.events as f64 / s / 1e6,
        n / s / 1e6
    );
}
