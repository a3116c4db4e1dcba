//! The collector search (nephele-runtime) on the default cumulus: time and table reads per
//! search, per order group, over the surface points of every 7th pixel of its camera (the
//! default light-space maps, 256², the shipped Mie 10 µm tables).
//!
//! And every group at once with the first read shared (`find_collectors`, as the renderer
//! searches). `cargo bench --bench collector`; reads per search are printed before the timings.

use criterion::{criterion_group, criterion_main, Criterion};
use nephele::render::fast::surface_points;
use nephele::render::scene::Scene;
use nephele_runtime::transport::{find_collector, find_collectors, SearchOptions};

fn bench(c: &mut Criterion) {
    let scene = Scene::parse(include_str!("../fit-configs/scenes/cloud.json")).unwrap();
    let (side, points) = surface_points(&scene, 7).unwrap();
    let tables = nephele_runtime::embedded::mie_10um();
    let sun = scene.sun.direction.map(|x| x as f32);
    let opts = SearchOptions::default();
    let mut group = c.benchmark_group("collector_search");
    for g in 0..tables.groups() {
        let (mut reads, mut found) = (0u64, 0u64);
        for v in &points {
            if let Some(f) = find_collector(&tables, g, &side, v, sun, &opts) {
                reads += f.reads as u64;
                found += 1;
            }
        }
        let first = tables.group_first_order(g).unwrap_or(0.0);
        println!(
            "orders {first}+: {:.2} reads per search over {found} of {} surface points",
            reads as f64 / found.max(1) as f64,
            points.len()
        );
        group.bench_function(
            format!("orders {first}+ ({} searches)", points.len()),
            |b| {
                b.iter(|| {
                    let mut t = 0.0f32;
                    for v in &points {
                        if let Some(f) = find_collector(&tables, g, &side, v, sun, &opts) {
                            t += f.transport.t;
                        }
                    }
                    t
                })
            },
        );
    }
    // Every group at once: the first read shared (find_collectors), as the renderer searches.
    group.bench_function(
        format!("all groups, first read shared ({} points)", points.len()),
        |b| {
            b.iter(|| {
                let mut t = 0.0f32;
                for v in &points {
                    let mut out = [None; 8];
                    find_collectors(&tables, &side, v, sun, &opts, &mut out);
                    t += out.iter().flatten().map(|f| f.transport.t).sum::<f32>();
                }
                t
            })
        },
    );
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = bench
}
criterion_main!(benches);
