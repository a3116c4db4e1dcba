//! Where a pixel's variance comes from: camera paths through the image centre of a scene, one
//! thread, per order group — the relative standard deviation of one path, the share of the
//! variance carried by the largest 0.01 %, 0.1 %, 1 % and 10 % of the paths (fireflies carry it
//! all in a few), and the time per path. Green channel, sunlight only (no sky).
//!
//!   cargo run --release --example path_stats -- fit-configs/scenes/cloud.json 16 100000
//!
//! (scene, sun-lobe steps K — 0 for plain NEE —, paths).

use nephele::phase::Phase;
use nephele::render::geometry::normalize;
use nephele::render::image::GROUP_FIRST;
use nephele::render::path::integrator::{trace, Volume};
use nephele::render::path::{volume, Settings};
use nephele::render::scene::Scene;
use rand::SeedableRng;

/// Mean, variance, and the variance share of the largest `fractions` of the squared deviations.
fn spread(values: &[f64], fractions: &[f64]) -> (f64, f64, Vec<f64>) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let mut sq: Vec<f64> = values.iter().map(|x| (x - mean).powi(2)).collect();
    let var = sq.iter().sum::<f64>() / n;
    sq.sort_by(|a, b| b.total_cmp(a));
    let shares = fractions
        .iter()
        .map(|f| {
            let k = ((f * n) as usize).max(1);
            sq[..k].iter().sum::<f64>() / (var * n)
        })
        .collect();
    (mean, var, shares)
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    anyhow::ensure!(args.len() == 4, "usage: path_stats SCENE K PATHS");
    let file = std::path::Path::new(&args[1]);
    let scene = Scene::load(file)?;
    let settings = Settings {
        sun_lobe_steps: args[2].parse()?,
        ..Settings::load(file)?
    };
    settings.validate()?;
    let steps = settings.sun_lobe_steps;
    let n: usize = args[3].parse()?;
    let medium = scene.build_medium()?;
    let surfaces = nephele::render::surface::Surfaces::build(&scene.surfaces)?;
    let models = Phase::build_channels(&scene.phase)?;
    Phase::with_all(&models, |phases| {
        // Sunlight only: the sky's share would blur where the variance comes from.
        let volume = Volume {
            sky: 0.0,
            ..volume(&scene, &settings, medium.as_ref(), &surfaces, phases)
        };
        let cam = &scene.camera;
        let dir = normalize(std::array::from_fn(|k| cam.look_at[k] - cam.position[k]));
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(5);
        let t0 = std::time::Instant::now();
        let groups: Vec<[f64; 9]> = (0..n)
            .map(|_| {
                let p = trace(&volume, cam.position, dir, &mut rng);
                std::array::from_fn(|g| p.groups[g][1])
            })
            .collect();
        let seconds = t0.elapsed().as_secs_f64();
        let totals: Vec<f64> = groups.iter().map(|g| g.iter().sum()).collect();
        let fractions = [1e-4, 1e-3, 1e-2, 0.1];
        let (mean, var, shares) = spread(&totals, &fractions);
        println!(
            "K = {steps} (lobe threshold {:.3} sr⁻¹): {n} paths in {seconds:.2} s ({:.1} µs/path); \
             mean {mean:.4e}, relative std per path {:.3}; variance share of the largest \
             0.01 / 0.1 / 1 / 10 %: {:.2} / {:.2} / {:.2} / {:.2}",
            volume.sun_lobe.threshold,
            1e6 * seconds / n as f64,
            var.sqrt() / mean,
            shares[0],
            shares[1],
            shares[2],
            shares[3]
        );
        for g in 0..GROUP_FIRST.len() {
            let values: Vec<f64> = groups.iter().map(|x| x[g]).collect();
            let (m, v, s) = spread(&values, &[1e-3]);
            println!(
                "  orders from {:>2}: {:5.1} % of the light, {:5.1} % of the variance, relative \
                 std per path {:6.2}, largest 0.1 % of paths {:.2} of its variance",
                GROUP_FIRST[g],
                100.0 * m / mean,
                100.0 * v / var,
                v.sqrt() / m,
                s[0]
            );
        }
    });
    Ok(())
}
