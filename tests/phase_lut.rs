//! Every model's renderer LUT (`icdf_mu` of `nephele phase`) samples its model in one
//! direction convention (docs/conventions.md, Sampling tables): it runs from μ = −1 at ξ = 0 to
//! +1 at ξ = 1 without decreasing, each entry sits at its quantile F(μᵢ) = ξᵢ of the model's
//! pdf integrated here, and the directions drawn from it, linearly interpolated in ξ as a
//! renderer would, pass the chi-square test against the model's pdf.
//!
//! Linear interpolation moves up to 1/(n − 1) of the probability inside one cell. Where the CDF
//! is flat over a whole cell (the back of a narrow lobe) that share spreads where the model has
//! none, which the chi-square test sees at 2·10⁵ samples for vMF κ = 20 with 1024 entries; the
//! chi-square therefore runs on 16384-entry tables and the quantile check on the default 1024.

mod common;

use common::cli::succeeds;
use nephele::phase::{build, Model, ModelParams};
use nephele::stats::adaptive_simpson;
use nephele::stats::chi2::{chi2_sphere, Chi2Config};
use nephele_runtime::phase::TabulatedTable;
use nephele_runtime::PhaseFunction;
use std::path::Path;

/// Each model with the flags of a typical cloud or aerosol setting.
const CASES: [(&str, &str); 11] = [
    ("hg", "--g 0.85"),
    ("two-term-hg", "--g 0.9 --g2 -0.4 --w 0.8"),
    ("cornette-shanks", "--g 0.8"),
    ("draine", "--g 0.6 --alpha 2"),
    ("hg-draine", "--diameter 10"),
    ("rayleigh", ""),
    ("reynolds-mccormick", "--g 0.7 --alpha 1"),
    ("schlick", "--k 0.6"),
    ("vmf", "--kappa 20"),
    ("xlf", "--g 0.4"),
    ("tabulated", "--table MIE"),
];

fn read(npz: &Path, name: &str) -> Vec<f64> {
    let mut a = npyz::npz::NpzArchive::open(npz).unwrap();
    a.by_name(name).unwrap().unwrap().into_vec().unwrap()
}

/// μ at ξ from the table, linear in ξ between entries.
fn lut_sample(icdf: &[f64], xi: f64) -> f64 {
    let x = xi * (icdf.len() - 1) as f64;
    let i = (x as usize).min(icdf.len() - 2);
    icdf[i] + (x - i as f64) * (icdf[i + 1] - icdf[i])
}

/// The model `nephele phase` tabulated, rebuilt here from the same flags.
fn model(name: &str, flags: &str, mie: &Path) -> Box<dyn Fn(f64) -> f64> {
    if name == "tabulated" {
        let th = read(mie, "theta_deg");
        let p = read(mie, "phase");
        let t = TabulatedTable::<f64>::from_phase(&th, &p).unwrap();
        return Box::new(move |mu| t.view().eval(mu));
    }
    let mut params = ModelParams::default();
    let words: Vec<&str> = flags.split_whitespace().collect();
    for kv in words.chunks(2) {
        let v: f64 = kv[1].parse().unwrap();
        match kv[0] {
            "--g" => params.g = Some(v),
            "--g2" => params.g2 = Some(v),
            "--w" => params.w = Some(v),
            "--alpha" => params.alpha = Some(v),
            "--diameter" => params.diameter = Some(v),
            "--k" => params.k = Some(v),
            "--kappa" => params.kappa = Some(v),
            f => panic!("flag {f}"),
        }
    }
    let m: Model = name.parse().unwrap();
    let built = build(m, &params).unwrap().0;
    Box::new(move |mu| built.eval(mu))
}

/// `icdf_mu` of `nephele phase --model NAME FLAGS --lut N`.
fn lut(dir: &Path, name: &str, flags: &str, n: usize) -> Vec<f64> {
    let out = dir.join(format!("{name}-{n}"));
    let n_s = n.to_string();
    let mut args = vec![
        "phase",
        "--model",
        name,
        "--lut",
        &n_s,
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(flags.split_whitespace());
    succeeds(&args);
    let icdf = read(&out.join("phase.npz"), "icdf_mu");
    assert_eq!(icdf.len(), n, "{name}");
    icdf
}

#[test]
fn every_models_lut_runs_from_back_to_forward_and_samples_its_pdf() {
    let dir = tempfile::tempdir().unwrap();
    let mie = dir.path().join("mie");
    succeeds(&[
        "mie",
        "--diameter",
        "5",
        "--sizes",
        "9",
        "--wavelengths",
        "550:550:1",
        "--out",
        mie.to_str().unwrap(),
    ]);
    let mie_npz = mie.join("phase.npz");
    let cfg = Chi2Config {
        n_mu: 50,
        n_phi: 4,
        samples: 200_000,
        ..Chi2Config::default()
    };
    let mut failures = vec![];
    for (name, flags) in CASES {
        let flags = flags.replace("MIE", mie_npz.to_str().unwrap());
        let m = model(name, &flags, &mie_npz);
        let icdf = lut(dir.path(), name, &flags, 1024);
        assert!(
            icdf[0] == -1.0 && icdf[1023] == 1.0,
            "{name}: icdf_mu runs {} → {}",
            icdf[0],
            icdf[1023]
        );
        if let Some(i) = (1..icdf.len()).find(|&i| icdf[i] < icdf[i - 1]) {
            failures.push(format!("{name}: icdf_mu decreases at entry {i}"));
        }
        // F(μᵢ) by adaptive Simpson from the last entry's μ (F(−1) = 0).
        let f = |mu: f64| 2.0 * std::f64::consts::PI * m(mu);
        let mut cdf = 0.0;
        for i in 1..icdf.len() {
            cdf += adaptive_simpson(&f, icdf[i - 1], icdf[i], 1e-12);
            let xi = i as f64 / 1023.0;
            if (cdf - xi).abs() > 1e-6 {
                failures.push(format!("{name}: F(icdf_mu[{i}]) = {cdf}, not {xi}"));
                break;
            }
        }
        let fine = lut(dir.path(), name, &flags, 16384);
        let r = chi2_sphere(
            &cfg,
            |a, b| {
                let mu = lut_sample(&fine, a);
                let s = (1.0 - mu * mu).max(0.0).sqrt();
                let phi = 2.0 * std::f64::consts::PI * b;
                [s * phi.cos(), s * phi.sin(), mu]
            },
            |d| m(d[2]),
        );
        if !r.passes(0.01, CASES.len()) {
            failures.push(format!("{name}: {r:?}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// `--export mitsuba` writes tabphase's values backward first on evenly spaced cosines (the
/// model's p at each, so HG's from its closed form), as XML and as load_dict JSON, and reports
/// in phase.json what the table loses (Mitsuba's own reading is checked by
/// scripts/check_mitsuba.py); a table of fewer than 2 nodes is refused, nothing written.
#[test]
fn mitsuba_export_writes_tabphase_backward_first() {
    let dir = std::env::temp_dir().join(format!("nephele-export-{}", std::process::id()));
    let export = |nodes: &'static str, out: &Path| -> Vec<String> {
        let flags = "phase --model hg --g 0.6 --export mitsuba --export-nodes";
        let mut args: Vec<String> = flags.split(' ').map(String::from).collect();
        args.extend([nodes.into(), "--out".into(), out.display().to_string()]);
        args
    };
    let args = export("1001", &dir);
    succeeds(&args.iter().map(String::as_str).collect::<Vec<_>>());
    let dict: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("phase_mitsuba.json")).unwrap()).unwrap();
    assert_eq!(dict["type"], "tabphase");
    let values: Vec<f64> = dict["values"]
        .as_str()
        .unwrap()
        .split(", ")
        .map(|v| v.parse().unwrap())
        .collect();
    assert_eq!(values.len(), 1001);
    let hg = |mu: f64| (1.0 - 0.36) / (4.0 * std::f64::consts::PI * (1.36 - 1.2 * mu).powf(1.5));
    for (i, v) in values.iter().enumerate() {
        let mu = -1.0 + 2.0 * i as f64 / 1000.0;
        assert!(
            (v / hg(mu) - 1.0).abs() < 1e-12,
            "node {i}: {v} vs {}",
            hg(mu)
        );
    }
    let xml = std::fs::read_to_string(dir.join("phase_mitsuba.xml")).unwrap();
    assert!(xml.contains(&format!("value=\"{}\"", dict["values"].as_str().unwrap())));
    let side: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("phase.json")).unwrap()).unwrap();
    let report = &side["mitsuba"];
    assert!((report["normalisation"].as_f64().unwrap() - 1.0).abs() < 1e-4);
    assert!((report["mean_cosine_as_mitsuba_reads_it"].as_f64().unwrap() - 0.6).abs() < 1e-4);
    let empty = dir.join("refused");
    let args = export("1", &empty);
    common::cli::refuses(
        &args.iter().map(String::as_str).collect::<Vec<_>>(),
        "--export-nodes",
        Some(&empty),
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
