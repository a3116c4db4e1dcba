//! The WGSL port's elementary functions (math.wgsl: exp, ln, eˣ − 1, sin and cos, asin) on a
//! real Vulkan driver against f64 over the ranges the port calls them on: within a few f32
//! ulps, where the drivers' built-ins may be thousands off.

mod common;
use common::{pipeline, run_kernel};

const KERNEL: &str = r#"
@group(0) @binding(0) var<uniform> job: vec4<u32>;
@group(0) @binding(1) var<storage, read> xs: array<f32>;
@group(0) @binding(2) var<storage, read_write> out: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= job.x {
        return;
    }
    let x = xs[i];
    let sc = nephele_sin_cos(x);
    var l = 0.0;
    if x > 0.0 {
        l = nephele_ln(x);
    }
    out[2u * i] = vec4<f32>(nephele_exp(x), l, nephele_exp_m1(x), sc.x);
    out[2u * i + 1u] = vec4<f32>(sc.y, nephele_asin(clamp(x, -1.0, 1.0)), 0.0, 0.0);
}
"#;

/// |got − want| in units of f32's spacing at want.
fn ulps(got: f32, want: f64) -> f64 {
    let w = want as f32;
    let spacing = (f32::from_bits(w.abs().to_bits() + 1) - w.abs()) as f64;
    if spacing == 0.0 || !spacing.is_finite() {
        return 0.0;
    }
    (got as f64 - want).abs() / spacing
}

#[test]
fn elementary_functions_within_a_few_ulps() {
    let mut xs: Vec<f32> = (0..200_000)
        .map(|i| {
            let r = i as f64 / 200_000.0;
            match i % 4 {
                0 => (-87.0 + 175.0 * r) as f32,           // exp's range
                1 => (-7.0 + 14.0 * r) as f32,             // sin, cos: ψ and θ
                2 => (10f64.powf(-6.0 + 12.0 * r)) as f32, // ln over decades
                _ => (-1.0 + 2.0 * r) as f32,              // eˣ − 1 and asin
            }
        })
        .collect();
    xs.extend([0.0, -0.0, 1.0, -1.0, 0.01, -0.01, 0.5, -0.5, 1e-30]);
    let job = [xs.len() as u32, 0, 0, 0];
    let kernel = pipeline("math", &format!("{}\n{}", nephele_wgsl::PHASE, KERNEL));
    let out = run_kernel(
        &kernel,
        job,
        &xs,
        None,
        32 * xs.len() as u64,
        xs.len() as u32,
    );
    let got: &[[f32; 4]] = bytemuck::cast_slice(&out);
    let mut worst = [(0.0f64, 0.0f32); 6];
    let names = ["exp", "ln", "exp_m1", "sin", "cos", "asin"];
    for (i, &x) in xs.iter().enumerate() {
        let xd = x as f64;
        let (a, b) = (got[2 * i], got[2 * i + 1]);
        let want = [
            xd.exp(),
            if x > 0.0 { xd.ln() } else { 0.0 },
            xd.exp_m1(),
            xd.sin(),
            xd.cos(),
            xd.clamp(-1.0, 1.0).asin(),
        ];
        let values = [a[0], a[1], a[2], a[3], b[0], b[1]];
        for k in 0..6 {
            // exp below f32's normal range is 0 on the GPU (flushed): not compared; sin and
            // cos are for angles (|x| ≤ 100 here), asin for |x| ≤ 1.
            if (k == 0 || k == 2) && want[0] < f32::MIN_POSITIVE as f64
                || (k == 3 || k == 4) && x.abs() > 100.0
                || k == 5 && x.abs() > 1.0
            {
                continue;
            }
            let e = ulps(values[k], want[k]);
            if e > worst[k].0 {
                worst[k] = (e, x);
            }
        }
    }
    for k in 0..6 {
        println!(
            "{}: {:.2} ulps at most (x = {:e})",
            names[k], worst[k].0, worst[k].1
        );
    }
    for k in 0..6 {
        assert!(
            worst[k].0 <= 4.0,
            "{}: {:.1} ulps at x = {:e}",
            names[k],
            worst[k].0,
            worst[k].1
        );
    }
}
