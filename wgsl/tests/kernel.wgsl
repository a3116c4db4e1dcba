// The test kernel around the port (tests/lavapipe.rs, tests/naga_outputs.rs); the
// tabulated model's table at @group(0) @binding(3) (nephele_wgsl::tabulated(0, 3)).
// Models: 0 HG(g), 1 Draine(g, α), 2 HG + Draine(g_HG, g_D, α, w_D), 3 HG + Draine of
// diameter p.x, 4 the tabulated table.
struct Job {
    mode: u32,
    model: u32,
    n: u32,
    pad: u32,
    p: vec4<f32>,
}
@group(0) @binding(0) var<uniform> job: Job;
@group(0) @binding(1) var<storage, read> inputs: array<vec2<f32>>;
@group(0) @binding(2) var<storage, read_write> outputs: array<vec4<f32>>;

fn blend(model: u32, p: vec4<f32>) -> NepheleHgDraine {
    if model == 3u {
        return nephele_hg_draine_from_diameter(p.x);
    }
    return NepheleHgDraine(p.x, p.y, p.z, p.w);
}

fn eval_model(model: u32, p: vec4<f32>, c: NepheleCosine) -> f32 {
    switch model {
        case 0u: { return nephele_hg_eval(p.x, c); }
        case 1u: { return nephele_draine_eval(p.x, p.y, c); }
        case 4u: { return nephele_tabulated_eval(c); }
        default: { return nephele_hg_draine_eval(blend(model, p), c); }
    }
}

fn sample_model(model: u32, p: vec4<f32>, xi: f32) -> NepheleCosine {
    switch model {
        case 0u: { return nephele_hg_sample(p.x, xi); }
        case 1u: { return nephele_draine_sample(p.x, p.y, xi); }
        case 4u: { return nephele_tabulated_sample(xi); }
        default: { return nephele_hg_draine_sample(blend(model, p), xi); }
    }
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= job.n {
        return;
    }
    let x = inputs[i];
    var out = vec4<f32>(0.0);
    if job.mode == 0u {
        out.x = eval_model(job.model, job.p, NepheleCosine(x.x, x.y));
    } else if job.mode == 1u {
        let c = sample_model(job.model, job.p, x.x);
        out = vec4<f32>(c.mu, c.one_minus_mu, 0.0, 0.0);
    } else {
        let m = nephele_hg_draine_from_diameter(x.x);
        out = vec4<f32>(m.g_hg, m.g_d, m.alpha, m.w_d);
    }
    outputs[i] = out;
}
