//! `nephele compress`: fits the compressed form to a slab run's tables and reports its error.

use anyhow::{ensure, Context, Result};
use clap::Args;
use nephele::compress::fit::{predict, predict_held_out};
use nephele::compress::joint::{fit_all_joint, fit_joint_groups, JointFit};
use nephele::compress::report::{group_error, group_error_on, GroupError};
use nephele::compress::ship::{ntt_bytes, phase_angles};
use nephele::compress::{fit_all, LogAdditive, SlabTables};
use nephele::io::{write_atomic, Npz};
use nephele::slab::tables::PhaseModel;
use nephele::slab::PhaseSpec;
use nephele_runtime::transport::tables::TransportTables;
use std::path::PathBuf;
use std::time::Instant;

/// Options of `nephele compress`.
#[derive(Args, Debug)]
pub struct CompressArgs {
    /// tables.npz of `nephele slab`.
    #[arg(long)]
    pub tables: PathBuf,
    /// Output directory (report.json, compressed.npz).
    #[arg(long)]
    pub out: PathBuf,
    /// Legendre terms in depth.
    #[arg(long, default_value_t = 6)]
    pub legendre: usize,
    /// Azimuth harmonics.
    #[arg(long, default_value_t = 3)]
    pub harmonics: usize,
    /// Nodes in the scattering angle.
    #[arg(long, default_value_t = 24)]
    pub theta_nodes: usize,
    /// Per-(μ_V, μ_L) γ, offset and depth slope.
    #[arg(long)]
    pub pairs: bool,
    /// Parameters as polynomials of degree Q − 1 in ln t fitted over all thicknesses at once
    /// (interpolates in t); 0 fits each thickness on its own.
    #[arg(long, default_value_t = 5)]
    pub smooth_t: usize,
    /// Skip the held-out study (a second fit without two thicknesses and two sun cosines,
    /// evaluated there by interpolation).
    #[arg(long)]
    pub no_held_out: bool,
}

/// Runs `nephele compress`.
pub fn run(args: CompressArgs) -> Result<()> {
    ensure!(
        args.smooth_t <= 9
            && (1..=16).contains(&args.legendre)
            && args.harmonics <= 8
            && (2..=512).contains(&args.theta_nodes),
        "--smooth-t in 0..=9, --legendre in 1..=16, --harmonics in 0..=8, --theta-nodes in 2..=512"
    );
    let form = LogAdditive {
        legendre: args.legendre,
        harmonics: args.harmonics,
        theta_nodes: args.theta_nodes,
        pairs: args.pairs,
    };
    let tab = SlabTables::load(&args.tables)?;
    ensure!(tab.shape[0] >= 2, "the tables hold no group of orders ≥ 2");
    let t0 = Instant::now();
    let fit = |skip_t: &[usize], skip_l: &[usize]| {
        if args.smooth_t == 0 {
            fit_all(&tab, &form, skip_t, skip_l)
        } else {
            fit_all_joint(&tab, &form, args.smooth_t, skip_t, skip_l)
        }
    };
    let (fits, joint) = if args.smooth_t == 0 {
        (fit_all(&tab, &form, &[], &[])?, Vec::new())
    } else {
        let joint = fit_joint_groups(&tab, &form, args.smooth_t, &[], &[])?;
        let tab = &tab;
        let fits = joint
            .iter()
            .flat_map(|j| (0..tab.shape[1]).map(move |it| j.at(tab, it)))
            .collect();
        (fits, joint)
    };
    let fit_s = t0.elapsed().as_secs_f64();
    let [ng, nt, nl, nd, nm, nk] = tab.shape;
    let slice = nl * nd * nm * nk;
    let mut pred = vec![0.0; tab.t.len()];
    for f in &fits {
        let start = (f.group * nt + f.it) * slice;
        pred[start..start + slice].copy_from_slice(&predict(&tab, &form, f));
    }
    let mut errors: Vec<_> = (1..ng).map(|g| group_error(&tab, &pred, Some(g))).collect();
    errors.push(group_error(&tab, &pred, None));
    print_errors("fitted slices", &errors);
    let held_out = if args.no_held_out {
        serde_json::Value::Null
    } else {
        // Inner thicknesses and sun cosines at a third and two thirds of their grids.
        let inner = |n: usize| -> Vec<usize> {
            let mut v: Vec<usize> = [n / 3, 2 * n / 3]
                .into_iter()
                .filter(|&i| i > 0 && i + 1 < n)
                .collect();
            v.dedup();
            v
        };
        let (skip_t, skip_l) = (inner(nt), inner(nl));
        let fits = fit(&skip_t, &skip_l)?;
        let pred = predict_held_out(&tab, &form, &fits, &skip_l);
        let held = |it: usize, il: usize| skip_t.contains(&it) || skip_l.contains(&il);
        let mut errors: Vec<_> = (1..ng)
            .map(|g| group_error_on(&tab, &pred, Some(g), &held))
            .collect();
        errors.push(group_error_on(&tab, &pred, None, &held));
        print_errors("held-out slices", &errors);
        serde_json::json!({
            "thicknesses": skip_t.iter().map(|&i| tab.thickness[i]).collect::<Vec<_>>(),
            "mu_l": skip_l.iter().map(|&i| tab.mu_l[i]).collect::<Vec<_>>(),
            "errors": errors,
        })
    };
    let params = form.n_params(nm, nl)
        * if args.smooth_t == 0 {
            fits.len()
        } else {
            (ng - 1) * args.smooth_t
        };
    println!(
        "{params} parameters ({:.0} KB as f32), fitted in {fit_s:.1} s",
        params as f64 * 4.0 / 1024.0
    );
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create '{}'", args.out.display()))?;
    let report = serde_json::json!({
        "tables": args.tables,
        "form": nephele::compress::form::to_json(&form),
        "smooth_t": args.smooth_t,
        "parameters": params,
        "fit_seconds": fit_s,
        "errors": errors,
        "held_out": held_out,
        "version": nephele::VERSION,
        "git_commit": option_env!("NEPHELE_GIT_COMMIT"),
    });
    write_atomic(&args.out.join("report.json"), |w| {
        serde_json::to_writer_pretty(&mut *w, &report)?;
        Ok(())
    })?;
    let mut npz = Npz::new();
    npz.add("T_form", &tab.shape, &pred);
    for f in &fits {
        npz.add(
            &format!("coef_g{}_t{}", f.group, f.it),
            &[f.coef.len()],
            &f.coef,
        );
    }
    write_atomic(&args.out.join("compressed.npz"), |w| npz.write_to(w))?;
    println!("wrote {}/report.json, compressed.npz", args.out.display());
    if !joint.is_empty() {
        write_ntt(&args, &tab, &form, &joint, &pred)?;
    }
    Ok(())
}

/// transport.ntt for renderers (joint fits only), checked by loading it back with the runtime:
/// its f32 evaluation against the fitted form (f64) on every cell the form represents.
fn write_ntt(
    args: &CompressArgs,
    tab: &SlabTables,
    form: &LogAdditive,
    joint: &[JointFit],
    pred: &[f64],
) -> Result<()> {
    let json = args.tables.with_extension("json");
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).with_context(|| {
            format!(
                "the phase function for order 1 comes from '{}'",
                json.display()
            )
        })?)
        .with_context(|| format!("'{}' is not JSON", json.display()))?;
    let spec: PhaseSpec = serde_json::from_value(doc["config"]["phase"].clone())
        .with_context(|| format!("'{}': no config.phase", json.display()))?;
    let model = PhaseModel::build(&spec)?;
    let phase: Vec<f64> = phase_angles()
        .iter()
        .map(|deg| model.with(|p| p.eval(deg.to_radians().cos())))
        .collect();
    let bytes = ntt_bytes(tab, form, args.smooth_t, joint, &phase)?;
    let rt = TransportTables::from_bytes(&bytes).map_err(|e| anyhow::anyhow!("{e}"))?;
    let [_, nt, nl, nd, nm, nk] = tab.shape;
    let mut worst = 0.0f64;
    for (gi, f) in joint.iter().enumerate() {
        for it in 0..nt {
            for il in 0..nl {
                for j in 0..nd {
                    for m in 0..nm {
                        for k in 0..nk {
                            let want = pred[tab.index(f.group, it, il, j, m, k)];
                            let (d, t) = (tab.depth[it * nd + j], tab.thickness[it]);
                            let got = rt.transport(
                                gi,
                                d as f32,
                                t as f32,
                                tab.mu_v(m) as f32,
                                tab.psi_v(k) as f32,
                                tab.mu_l[il] as f32,
                            ) as f64;
                            if want > 0.0 && got > 0.0 {
                                worst = worst.max((got / want - 1.0).abs());
                            }
                        }
                    }
                }
            }
        }
    }
    let path = args.out.join("transport.ntt");
    nephele::io::write_atomic(&path, |w| {
        std::io::Write::write_all(w, &bytes)?;
        Ok(())
    })?;
    println!(
        "wrote {} ({:.0} KB); the runtime's f32 evaluation within {:.1e} of the fitted form",
        path.display(),
        bytes.len() as f64 / 1024.0,
        worst
    );
    Ok(())
}

fn print_errors(what: &str, errors: &[GroupError]) {
    println!("{what}: group  orders   E (T-weighted rel RMS)   noise    cells");
    for e in errors {
        let name = e
            .first_order
            .map_or("sum ≥ 2".to_string(), |o| format!("{o:>4}+"));
        let group = e.group.map_or("all".into(), |g| g.to_string());
        println!(
            "{:>w$}  {group:>5}  {name:>7}   {:>8.2} %               {:>5.2} %  {:>7}",
            "",
            100.0 * e.rel_rms,
            100.0 * e.noise,
            e.cells,
            w = what.len()
        );
    }
}
