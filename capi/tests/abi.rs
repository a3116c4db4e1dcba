//! The C ABI: its header is what cbindgen writes from the source (NEPHELE_BLESS=1 rewrites it),
//! a C program compiled by the system C compiler under AddressSanitizer and
//! UndefinedBehaviorSanitizer answers as the Rust runtime does bit for bit, bad input gets its
//! status code, and truncated or bit-flipped tables are refused without a crash.

use nephele_c::*;
use nephele_runtime::embedded::{mie_10um, MIE_10UM};
use nephele_runtime::phase::{HgDraine, TabulatedTable};
use nephele_runtime::transport::{
    find_collectors, finite_cloud, Clamps, Collector, FilteredSurface, FiniteCloud, Lateral,
    LitSurface, SearchOptions, SlabPoint, Transport, TransportTables, Viewpoint,
};
use nephele_runtime::PhaseFunction;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

fn crate_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn the_header_is_cbindgens() {
    let dir = crate_dir();
    let config = cbindgen::Config::from_file(dir.join("cbindgen.toml")).unwrap();
    let mut generated = Vec::new();
    cbindgen::Builder::new()
        .with_crate(&dir)
        .with_config(config)
        .generate()
        .expect("cbindgen")
        .write(&mut generated);
    let path = dir.join("include/nephele.h");
    if std::env::var_os("NEPHELE_BLESS").is_some() {
        std::fs::write(&path, &generated).unwrap();
    }
    let committed = std::fs::read(&path).unwrap_or_default();
    assert!(
        committed == generated,
        "include/nephele.h is not what cbindgen writes from src/lib.rs: run \
         NEPHELE_BLESS=1 cargo test -p nephele-c --test abi"
    );
}

/// The static library cargo built beside this test.
fn static_library() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let deps = exe.parent().unwrap();
    [deps.to_path_buf(), deps.parent().unwrap().to_path_buf()]
        .iter()
        .map(|d| d.join("libnephele_c.a"))
        .find(|p| p.exists())
        .expect("libnephele_c.a beside the test binary")
}

/// `source` compiled by the system C compiler ($CC or cc) against the static library into
/// `exe`, strictly (C99, every warning an error), with `extra` flags.
fn compile_c(source: &Path, exe: &Path, extra: &[&str]) {
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    let built = Command::new(&cc)
        .args(["-std=c99", "-Wall", "-Wextra", "-Werror", "-g", "-O1"])
        .args(extra)
        .arg("-I")
        .arg(crate_dir().join("include"))
        .arg(source)
        .arg(static_library())
        .args(["-lm", "-lpthread", "-ldl", "-o"])
        .arg(exe)
        .output()
        .expect("run the C compiler");
    assert!(
        built.status.success(),
        "{cc}: {}",
        String::from_utf8_lossy(&built.stderr)
    );
}

/// Points over the whole domain: faces, the horizon (±0), grid edges and beyond, random.
fn points() -> Vec<[f32; 5]> {
    // 3.14159: a ψ just short of π, not the constant.
    #[allow(clippy::approx_constant)]
    let mut p = vec![
        [4.0, 0.5, 0.0, -0.3, 0.1],
        [4.0, 0.5, 4.0, 0.3, 3.0],
        [4.0, 0.5, 2.0, 0.0, 0.0],
        [4.0, 0.5, 2.0, -0.0, 0.0],
        [0.5, 0.125, 0.25, 1.0, 1.5],
        [128.0, 1.0, 127.0, -1.0, 3.14159],
        [500.0, 0.02, 10.0, 0.5, 0.7],
        [4.0, 0.5, 5.0, 0.3, 0.0],
    ];
    let mut rng = nephele_stats::XorShift64::new(0x9E3779B97F4A7C15);
    let mut r = || rng.unit_f32();
    for _ in 0..500 {
        let t = 0.5 * 256f32.powf(r());
        p.push([
            t,
            0.125 + 0.875 * r(),
            t * r(),
            2.0 * r() - 1.0,
            std::f32::consts::TAU * r() - std::f32::consts::PI,
        ]);
    }
    p
}

#[test]
fn a_c_program_under_sanitizers_answers_as_the_runtime() {
    let tmp = std::env::temp_dir().join(format!("nephele-capi-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    let exe = tmp.join("nephele_example");
    let source = crate_dir().join("../examples/c/nephele_example.c");
    compile_c(
        &source,
        &exe,
        &["-fsanitize=address,undefined", "-fno-sanitize-recover=all"],
    );
    let pts = points();
    let mut child = Command::new(&exe)
        .arg(crate_dir().join("../runtime/tables/mie10um/transport.ntt"))
        .env("ASAN_OPTIONS", "detect_leaks=1:abort_on_error=1")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    {
        let mut input = child.stdin.take().unwrap();
        for p in &pts {
            let line: Vec<String> = p.iter().map(|v| format!("{:08x}", v.to_bits())).collect();
            writeln!(input, "{}", line.join(" ")).unwrap();
        }
    }
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "the C example failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let tab = mie_10um();
    let hex = |v: f32| format!("{:08x}", v.to_bits());
    let d = tab.domain();
    assert_eq!(
        lines[0],
        format!(
            "domain {} {} {} {} {} {} 1",
            hex(d.thickness.0),
            hex(d.thickness.1),
            hex(d.mu_l.0),
            hex(d.mu_l.1),
            hex(tab.mean_cosine()),
            tab.groups()
        )
    );
    let mut all = [Transport::default(); 8];
    let mut inside = 0;
    for (p, line) in pts.iter().zip(&lines[1..]) {
        let at = SlabPoint {
            thickness: p[0],
            mu_l: p[1],
            depth: p[2],
            mu_v: p[3],
            psi_v: p[4],
        };
        if at.check().is_err() {
            assert_eq!(*line, "bad_point 6", "{p:?}");
            continue;
        }
        inside += 1;
        tab.evaluate_all(&at, &mut all);
        let mut want = vec![hex(tab.order1(&at))];
        for v in &all {
            want.extend([hex(v.t), hex(v.c_x), hex(v.c_z), hex(v.sigma)]);
        }
        want.push(d.outside(&at).bits(&d).to_string());
        assert_eq!(line.split(' ').collect::<Vec<_>>(), want, "{p:?}");
    }
    assert!(inside < pts.len(), "no point outside the slab was tried");
    assert!(
        lines.contains(&format!("batch {inside} 1").as_str()),
        "the batch differs from the points one by one"
    );
    let phase = HgDraine::<f32>::from_diameter(10.0);
    let phase_lines: Vec<&&str> = lines.iter().filter(|l| l.starts_with("phase ")).collect();
    assert_eq!(phase_lines.len(), 9);
    for (i, line) in phase_lines.iter().enumerate() {
        let (mu, xi) = (-1.0f32 + 0.25 * i as f32, 0.125f32 * i as f32);
        let want = format!(
            "phase {} {} {}",
            hex(phase.eval(mu)),
            hex(phase.pdf(mu)),
            hex(phase.sample_mu(xi))
        );
        assert_eq!(**line, want);
    }
    let (theta, table): (Vec<f64>, Vec<f64>) = (0..=360)
        .map(|i| {
            let theta = 0.5 * i as f64;
            let d = 1.0 + 0.85 * 0.85 - 2.0 * 0.85 * (theta * std::f64::consts::PI / 180.0).cos();
            (
                theta,
                (1.0 - 0.85 * 0.85) / (4.0 * std::f64::consts::PI * d * d.sqrt()),
            )
        })
        .unzip();
    let tabulated = TabulatedTable::<f32>::from_phase(&theta, &table).unwrap();
    let tab_lines: Vec<&&str> = lines
        .iter()
        .filter(|l| l.starts_with("tabulated "))
        .collect();
    assert_eq!(tab_lines.len(), 9);
    for (i, line) in tab_lines.iter().enumerate() {
        let (mu, xi) = (-1.0f32 + 0.25 * i as f32, 0.125f32 * i as f32);
        let p = tabulated.view();
        assert_eq!(
            **line,
            format!("tabulated {} {}", hex(p.eval(mu)), hex(p.sample_mu(xi)))
        );
    }
    the_collectors_are_the_runtimes(&lines, &tab);
    let status = |case: &str| -> i32 {
        let line = lines
            .iter()
            .find(|l| l.starts_with(&format!("status {case} ")))
            .unwrap_or_else(|| panic!("no status line for {case}"));
        line.split(' ').nth(2).unwrap().parse().unwrap()
    };
    for (case, code) in [
        ("null_bytes", NepheleStatus::NullPointer),
        ("null_out", NepheleStatus::NullPointer),
        ("truncated", NepheleStatus::BadTables),
        ("empty", NepheleStatus::BadTables),
        ("corrupt", NepheleStatus::BadTables),
        ("version", NepheleStatus::BadTables),
        ("null_tables", NepheleStatus::NullPointer),
        ("null_point", NepheleStatus::NullPointer),
        ("bad_group", NepheleStatus::BadGroup),
        ("short_out", NepheleStatus::BadArgument),
        ("bad_g", NepheleStatus::BadArgument),
        ("bad_mu", NepheleStatus::BadArgument),
        ("bad_diameter", NepheleStatus::BadArgument),
        ("null_surface", NepheleStatus::NullPointer),
        ("null_callback", NepheleStatus::NullPointer),
        ("collector_group", NepheleStatus::BadGroup),
        ("not_unit_sun", NepheleStatus::BadArgument),
        ("short_collectors", NepheleStatus::BadArgument),
        ("not_found", NepheleStatus::BadArgument),
        ("bad_table", NepheleStatus::BadArgument),
        ("batch_bad_point", NepheleStatus::BadPoint),
        ("batch_stride", NepheleStatus::BadArgument),
        ("missing_file", NepheleStatus::Io),
    ] {
        assert_eq!(status(case), code as i32, "{case}");
    }
    assert_eq!(
        status("batch_untouched"),
        1,
        "a refused batch wrote its output"
    );
    assert_eq!(
        status("cleared"),
        1,
        "a successful call left the last error"
    );
    // Every entry refuses every point outside the slab, and says which coordinate.
    for i in 0..6 {
        let line = lines
            .iter()
            .find(|l| l.starts_with(&format!("status point_{i} ")))
            .unwrap();
        assert_eq!(
            line.split(' ').skip(2).collect::<Vec<_>>(),
            ["6", "6", "6"],
            "{line}"
        );
    }
    let message = |case: &str| -> String {
        let head = format!("message {case} ");
        lines
            .iter()
            .find(|l| l.starts_with(&head))
            .unwrap_or_else(|| panic!("no message line for {case}"))[head.len()..]
            .to_string()
    };
    for (i, says) in [
        "mu_L = 1.5 is not a sun cosine",
        "mu_V = 2 is not a cosine",
        "mu_L = NaN is not a sun cosine",
        "t = inf mfp is not a thickness",
        "depth = 5 mfp is outside the slab [0, t = 4]",
        "psi_V = -inf rad is not a finite angle",
    ]
    .iter()
    .enumerate()
    {
        let m = message(&format!("point_{i}"));
        assert!(m.contains(says), "point {i}: {m}");
    }
    assert!(message("batch_bad_point").starts_with("point 2: mu_L = 1.5"));
    let truncated = message("truncated");
    assert!(
        truncated.starts_with("truncated transport tables"),
        "{truncated}"
    );
    assert!(
        !truncated.contains("tables: transport tables"),
        "{truncated}"
    );
    let foreign = message("foreign");
    assert!(
        foreign.contains("not a nephele transport tables file"),
        "{foreign}"
    );
    assert!(message("missing_file").contains("'/nonexistent/x.ntt'"));
    let version = lines
        .iter()
        .find(|l| l.starts_with("status version"))
        .unwrap();
    assert!(version.contains("version 9"), "{version}");
    std::fs::remove_dir_all(&tmp).unwrap();
}

/// One handle shared by two of the caller's threads, each running the batch entry on its own
/// half of the points (examples/c/nephele_threads.c, under ThreadSanitizer where the compiler
/// has it): every answer is the one thread's, bit for bit.
#[test]
fn two_threads_share_one_handle_and_answer_as_one() {
    let tmp = std::env::temp_dir().join(format!("nephele-capi-threads-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    let exe = tmp.join("nephele_threads");
    compile_c(
        &crate_dir().join("../examples/c/nephele_threads.c"),
        &exe,
        &[],
    );
    let out = Command::new(&exe)
        .arg(crate_dir().join("../runtime/tables/mie10um/transport.ntt"))
        .args(["20000", "2", "1"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.lines().any(|l| l == "identical 1"), "{text}");
    std::fs::remove_dir_all(&tmp).unwrap();
}

/// The library's version macros are the crate's, and the shared library's SONAME carries the
/// ABI version.
#[test]
fn the_versions_and_the_soname_agree() {
    assert_eq!(
        NEPHELE_VERSION_MAJOR.to_string(),
        env!("CARGO_PKG_VERSION_MAJOR")
    );
    assert_eq!(
        NEPHELE_VERSION_MINOR.to_string(),
        env!("CARGO_PKG_VERSION_MINOR")
    );
    assert_eq!(
        NEPHELE_VERSION_PATCH.to_string(),
        env!("CARGO_PKG_VERSION_PATCH")
    );
    assert_eq!(nephele_abi_version(), NEPHELE_ABI_VERSION);
    let build = std::fs::read_to_string(crate_dir().join("build.rs")).unwrap();
    assert!(
        build.contains(&format!("const ABI_VERSION: u32 = {NEPHELE_ABI_VERSION};")),
        "capi/build.rs sets the SONAME from another ABI version"
    );
    let lib = static_library().with_file_name("libnephele_c.so");
    if let Ok(out) = Command::new("readelf").arg("-d").arg(&lib).output() {
        if out.status.success() {
            let text = String::from_utf8_lossy(&out.stdout);
            let want = format!("[libnephele_c.so.{NEPHELE_ABI_VERSION}]");
            assert!(text.contains(&want), "{}: no SONAME {want}", lib.display());
        }
    }
}

/// The C example's sphere of cloud (examples/c/nephele_example.c), the same f32 operations in
/// the same order: radius (m), extinction (1/m), the sun.
struct Sphere {
    radius: f32,
    kappa: f32,
}

const SUN: [f32; 3] = [0.0, 0.6, 0.8];

impl Sphere {
    fn line_disc(&self, at: [f32; 3]) -> (f32, f32) {
        let b = at[0] * SUN[0] + at[1] * SUN[1] + at[2] * SUN[2];
        let c = at[0] * at[0] + at[1] * at[1] + at[2] * at[2] - self.radius * self.radius;
        (b * b - c, b)
    }
}

impl LitSurface for Sphere {
    fn filtered(&self, at: [f32; 3], _sigma: f32) -> Option<FilteredSurface> {
        let (disc, b) = self.line_disc(at);
        if !(disc > 0.0) {
            return None;
        }
        let h = disc.sqrt();
        let entry: [f32; 3] = std::array::from_fn(|k| at[k] + (h - b) * SUN[k]);
        Some(FilteredSurface {
            entry,
            normal: entry.map(|e| e / self.radius),
            length: 2.0 * h,
            optical_length: self.kappa * (2.0 * h),
        })
    }

    fn initial_scale(&self) -> f32 {
        self.radius
    }

    fn lateral(&self, at: [f32; 3], _sigma: f32) -> Option<Lateral> {
        let (disc, b) = self.line_disc(at);
        if !(disc > 0.0) {
            return None;
        }
        let rho2 = at[0] * at[0] + at[1] * at[1] + at[2] * at[2] - b * b;
        Some(Lateral {
            coverage: 1.0,
            edge_distance: self.radius - rho2.max(0.0).sqrt(),
        })
    }

    fn sun_depth(&self, at: [f32; 3]) -> Option<f32> {
        let (disc, b) = self.line_disc(at);
        let d = if disc > 0.0 { disc.sqrt() - b } else { 0.0 };
        Some(self.kappa * d.max(0.0))
    }
}

/// The C example's viewpoint `i`.
fn viewpoint(i: usize) -> Viewpoint {
    let views = [
        [0.0, 0.0, 1.0],
        [0.6, 0.0, 0.8],
        [0.0, -0.6, -0.8],
        [1.0, 0.0, 0.0],
    ];
    let k = (i / 4) as f32;
    let v = Viewpoint::new(
        [120.0 * k - 150.0, 60.0 * k - 80.0, 50.0 * k - 100.0],
        views[i % 4],
    );
    if i >= 12 {
        Viewpoint {
            behind_min: 1.0,
            behind_max: 2.0,
            sun_depth: 1.0,
            ..v
        }
    } else {
        v
    }
}

/// The C program's "collector" lines against the runtime's search and finite-cloud correction
/// on the same sphere, bit for bit.
fn the_collectors_are_the_runtimes(lines: &[&str], tab: &TransportTables) {
    let sphere = Sphere {
        radius: 500.0,
        kappa: 0.05,
    };
    let finite = FiniteCloud::for_tables(tab);
    let hex = |v: f32| format!("{:08x}", v.to_bits());
    let got: Vec<&&str> = lines
        .iter()
        .filter(|l| l.starts_with("collector "))
        .collect();
    let mut want = Vec::new();
    let mut found = 0;
    for i in 0..16 {
        let mut all = [None; 8];
        find_collectors(
            tab,
            &sphere,
            &viewpoint(i),
            SUN,
            &SearchOptions::for_tables(tab),
            &mut all,
        );
        for (g, c) in all.iter().enumerate() {
            let mut line = format!("collector {i} {g}");
            let (c, kept) = match c {
                Some(c) => {
                    found += 1;
                    let k = finite_cloud(tab, g, &sphere, c, &finite);
                    let clamps = u32::from(c.clamps.thickness)
                        | u32::from(c.clamps.mu_l) << 1
                        | u32::from(c.clamps.depth) << 2
                        | u32::from(c.clamps.view) << 3
                        | u32::from(c.clamps.sun) << 4;
                    line += &format!(" 1 {} {} {clamps}", c.reads, u32::from(c.converged));
                    (*c, [k.factor, k.radius, k.coverage])
                }
                None => {
                    line += " 0 0 0 0";
                    let zero = Collector {
                        transport: Transport::default(),
                        at: SlabPoint {
                            depth: 0.0,
                            thickness: 0.0,
                            mu_v: 0.0,
                            psi_v: 0.0,
                            mu_l: 0.0,
                        },
                        centre: [0.0; 3],
                        sigma: 0.0,
                        reads: 0,
                        converged: false,
                        clamps: Clamps::default(),
                        unheld: Default::default(),
                        extinction: 0.0,
                    };
                    (zero, [1.0, f32::INFINITY, 1.0])
                }
            };
            let t = c.transport;
            for v in [
                t.t,
                t.c_x,
                t.c_z,
                t.sigma,
                c.centre[0],
                c.centre[1],
                c.centre[2],
            ]
            .into_iter()
            .chain([c.sigma, c.extinction])
            .chain(kept)
            {
                line += &format!(" {}", hex(v));
            }
            want.push(line);
        }
    }
    assert_eq!(got.len(), want.len());
    for (g, w) in got.iter().zip(&want) {
        assert_eq!(**g, w.as_str());
    }
    // The sphere is lit from above and the viewpoints are inside it: most groups find one.
    assert!(found > want.len() / 2, "{found} of {} found", want.len());
}

/// Every 97th truncation and 3000 bit flips of the shipped file through the ABI: each refused
/// with a status and a message or (a flip the checksum does not cover) loaded and answering
/// finite values; no panic crosses the boundary.
#[test]
fn truncated_and_corrupt_tables_are_refused_without_a_crash() {
    let load = |bytes: &[u8]| -> (NepheleStatus, *mut NepheleTables) {
        let mut t = std::ptr::null_mut();
        let s = unsafe { nephele_tables_from_bytes(bytes.as_ptr(), bytes.len(), &mut t) };
        (s, t)
    };
    let message = || {
        unsafe { std::ffi::CStr::from_ptr(nephele_last_error()) }
            .to_string_lossy()
            .into_owned()
    };
    for n in (0..MIE_10UM.len()).step_by(97) {
        let (s, t) = load(&MIE_10UM[..n]);
        assert_eq!(s, NepheleStatus::BadTables, "truncated at {n}");
        assert!(
            t.is_null() && message().starts_with("truncated transport tables"),
            "{}",
            message()
        );
    }
    let mut rng = nephele_stats::XorShift64::new(0x2545F4914F6CDD1D);
    let at = NepheleSlabPoint {
        thickness: 8.0,
        mu_l: 0.6,
        depth: 3.0,
        mu_v: -0.4,
        psi_v: 1.0,
    };
    let mut loaded = 0;
    for _ in 0..3000 {
        let state = rng.next_u64();
        let mut bytes = MIE_10UM.to_vec();
        let bit = (state % (8 * bytes.len() as u64)) as usize;
        bytes[bit / 8] ^= 1 << (bit % 8);
        let (s, t) = load(&bytes);
        if s == NepheleStatus::Ok {
            loaded += 1;
            let mut out = [NepheleTransport::default(); NEPHELE_MAX_GROUPS];
            let r = unsafe { nephele_evaluate_all(t, &at, out.as_mut_ptr(), out.len()) };
            assert_eq!(r, NepheleStatus::Ok);
            unsafe { nephele_tables_free(t) };
        } else {
            assert_eq!(s, NepheleStatus::BadTables);
            assert!(t.is_null() && !message().is_empty());
        }
    }
    // The CRC-32 covers every byte but its own: a flip there alone can load.
    assert!(loaded <= 3000 / 100, "{loaded} flipped files loaded");
}

/// The ABI's answers for one point are the runtime's, through every entry point.
#[test]
fn the_entry_points_answer_as_the_runtime() {
    let mut t = std::ptr::null_mut();
    assert_eq!(
        unsafe { nephele_tables_embedded(&mut t) },
        NepheleStatus::Ok
    );
    let tab = mie_10um();
    let at = NepheleSlabPoint {
        thickness: 8.0,
        mu_l: 0.6,
        depth: 3.0,
        mu_v: -0.4,
        psi_v: 1.0,
    };
    let rt = SlabPoint {
        thickness: at.thickness,
        mu_l: at.mu_l,
        depth: at.depth,
        mu_v: at.mu_v,
        psi_v: at.psi_v,
    };
    let mut weight = 0.0f32;
    assert_eq!(
        unsafe { nephele_view_weight(&at, 0.4, &mut weight) },
        NepheleStatus::Ok
    );
    assert_eq!(weight.to_bits(), rt.view_weight(0.4).to_bits());
    assert_eq!(
        unsafe { nephele_view_weight(&at, 1.5, &mut weight) },
        NepheleStatus::BadArgument
    );
    let mut groups = 0usize;
    assert_eq!(
        unsafe { nephele_tables_groups(t, &mut groups) },
        NepheleStatus::Ok
    );
    assert_eq!(groups, tab.groups());
    let mut ts = [0.0f32; NEPHELE_MAX_GROUPS];
    assert_eq!(
        unsafe { nephele_transport_all(t, &at, ts.as_mut_ptr(), ts.len()) },
        NepheleStatus::Ok
    );
    for g in 0..groups {
        let mut one = NepheleTransport::default();
        assert_eq!(
            unsafe { nephele_evaluate(t, g, &at, &mut one) },
            NepheleStatus::Ok
        );
        let want = tab.evaluate(g, &rt);
        assert_eq!(
            [one.t, one.c_x, one.c_z, one.sigma].map(f32::to_bits),
            [want.t, want.c_x, want.c_z, want.sigma].map(f32::to_bits)
        );
        assert_eq!(ts[g].to_bits(), want.t.to_bits());
        let mut first = 0.0;
        assert_eq!(
            unsafe { nephele_tables_group_first_order(t, g, &mut first) },
            NepheleStatus::Ok
        );
        assert_eq!(Some(first), tab.group_first_order(g));
    }
    let mut first = 0.0;
    assert_eq!(
        unsafe { nephele_tables_group_first_order(t, groups, &mut first) },
        NepheleStatus::BadGroup
    );
    unsafe { nephele_tables_free(t) };
    let v = unsafe { std::ffi::CStr::from_ptr(nephele_version()) };
    assert_eq!(v.to_str().unwrap(), nephele_runtime::VERSION);
    assert!(Path::new(&crate_dir().join("include/nephele.h")).exists());
}
