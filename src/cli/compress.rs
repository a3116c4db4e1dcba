//! `nephele compress`: fits the compressed form to a slab run's tables and reports its error.

use anyhow::{ensure, Context, Result};
use clap::Args;
use nephele::compress::fit::{predict, predict_held_out};
use nephele::compress::joint::fit_all_joint;
use nephele::compress::report::{group_error, group_error_on, GroupError};
use nephele::compress::{fit_all, LogAdditive, SlabTables};
use nephele::io::{write_atomic, Npz};
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
    let fits = fit(&[], &[])?;
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
