//! The C ABI fed what a careless or hostile caller passes, the way the Rust loader is fuzzed
//! (proptest, thousands of cases): random and damaged table bytes, points of any f32 bits (NaN,
//! ±inf, ±0, subnormals), phase parameters of any value, groups and capacities out of range,
//! collector searches from any viewpoint with any sun. Every call returns a status; none
//! panics across the boundary (a caught panic is `NEPHELE_STATUS_PANIC`, a bug), and the
//! values of a call that succeeds are finite.

use nephele_c::*;
use nephele_runtime::embedded::MIE_10UM;
use nephele_runtime::transport::SlabPoint;
use proptest::prelude::*;
use std::ffi::c_void;
use std::sync::OnceLock;

/// The shipped tables through the ABI, once.
fn tables() -> &'static Tables {
    static T: OnceLock<Tables> = OnceLock::new();
    T.get_or_init(|| {
        let mut t = std::ptr::null_mut();
        let s = unsafe { nephele_tables_from_bytes(MIE_10UM.as_ptr(), MIE_10UM.len(), &mut t) };
        assert_eq!(s, NepheleStatus::Ok);
        Tables(t)
    })
}

struct Tables(*mut NepheleTables);
// SAFETY: the tables are immutable after loading; the ABI's calls only read them.
unsafe impl Send for Tables {}
unsafe impl Sync for Tables {}

fn any_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        any::<u32>().prop_map(f32::from_bits),
        Just(f32::NAN),
        Just(f32::INFINITY),
        Just(f32::NEG_INFINITY),
        Just(0.0f32),
        Just(-0.0f32),
        -2.0f32..2.0,
        0.0f32..300.0,
    ]
}

fn finite(values: &[f32]) -> bool {
    values.iter().all(|v| v.is_finite())
}

/// A unit sphere of cloud of radius 100 m, as a C caller would write it.
unsafe extern "C" fn sphere(
    _user: *mut c_void,
    at: *const f32,
    _sigma: f32,
    out: *mut NepheleFilteredSurface,
) -> i32 {
    let at = unsafe { std::slice::from_raw_parts(at, 3) };
    let sun = [0.0f32, 0.6, 0.8];
    let b: f32 = at.iter().zip(sun).map(|(a, s)| a * s).sum();
    let disc = b * b - (at.iter().map(|a| a * a).sum::<f32>() - 1e4);
    if !(disc > 0.0) {
        return 0;
    }
    let h = disc.sqrt();
    let out = unsafe { &mut *out };
    for k in 0..3 {
        out.entry[k] = at[k] + (h - b) * sun[k];
        out.normal[k] = out.entry[k] / 100.0;
    }
    out.length = 2.0 * h;
    out.optical_length = 0.05 * out.length;
    1
}

/// The same sphere's optical depth to the sun: known (1) where the light line crosses it.
unsafe extern "C" fn sphere_sun_depth(_user: *mut c_void, at: *const f32, out: *mut f32) -> i32 {
    let at = unsafe { std::slice::from_raw_parts(at, 3) };
    let sun = [0.0f32, 0.6, 0.8];
    let b: f32 = at.iter().zip(sun).map(|(a, s)| a * s).sum();
    let disc = b * b - (at.iter().map(|a| a * a).sum::<f32>() - 1e4);
    unsafe { *out = 0.05 * (disc.max(0.0).sqrt() - b).max(0.0) };
    1
}

proptest! {
    // A fixed seed: CI runs the same 2 000 cases per property every time (set PROPTEST_CASES
    // or change the seed to explore further).
    #![proptest_config(ProptestConfig {
        cases: 2000,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x6e_65_70_68_65_6c_65),
        ..ProptestConfig::default()
    })]

    #[test]
    fn random_bytes_are_refused_or_loaded(bytes in proptest::collection::vec(any::<u8>(), 0..4000)) {
        let mut t = std::ptr::null_mut();
        let s = unsafe { nephele_tables_from_bytes(bytes.as_ptr(), bytes.len(), &mut t) };
        prop_assert!(s == NepheleStatus::BadTables || s == NepheleStatus::Ok, "{s:?}");
        prop_assert_eq!(t.is_null(), s != NepheleStatus::Ok);
        unsafe { nephele_tables_free(t) };
    }

    #[test]
    fn damaged_tables_are_refused_or_answer(at in 0usize..MIE_10UM.len(), byte in any::<u8>(), cut in any::<bool>()) {
        let mut bytes = MIE_10UM.to_vec();
        if cut { bytes.truncate(at) } else { bytes[at] = byte }
        let mut t = std::ptr::null_mut();
        let s = unsafe { nephele_tables_from_bytes(bytes.as_ptr(), bytes.len(), &mut t) };
        prop_assert!(s == NepheleStatus::BadTables || s == NepheleStatus::Ok, "{s:?}");
        if s == NepheleStatus::Ok {
            let p = NepheleSlabPoint { thickness: 8.0, mu_l: 0.6, depth: 2.0, mu_v: 0.3, psi_v: 1.0 };
            let mut out = [NepheleTransport::default(); NEPHELE_MAX_GROUPS];
            let e = unsafe { nephele_evaluate_all(t, &p, out.as_mut_ptr(), out.len()) };
            prop_assert_eq!(e, NepheleStatus::Ok);
        }
        unsafe { nephele_tables_free(t) };
    }

    #[test]
    fn any_point_and_group_gets_a_status_and_finite_values(
        p in prop::array::uniform5(any_f32()),
        group in 0usize..80,
        capacity in 0usize..80,
    ) {
        let t = tables().0;
        let at = NepheleSlabPoint { thickness: p[0], mu_l: p[1], depth: p[2], mu_v: p[3], psi_v: p[4] };
        // A point outside the slab is BAD_POINT from every entry, whatever the other arguments.
        let valid = SlabPoint { thickness: p[0], mu_l: p[1], depth: p[2], mu_v: p[3], psi_v: p[4] }
            .check()
            .is_ok();
        let mut one = NepheleTransport::default();
        let s = unsafe { nephele_evaluate(t, group, &at, &mut one) };
        let want = if group >= 8 { NepheleStatus::BadGroup } else if !valid { NepheleStatus::BadPoint } else { NepheleStatus::Ok };
        prop_assert_eq!(s, want);
        if s == NepheleStatus::Ok {
            prop_assert!(finite(&[one.t, one.c_x, one.c_z, one.sigma]), "{at:?} → {one:?}");
        }
        let mut all = vec![NepheleTransport::default(); capacity];
        let s = unsafe { nephele_evaluate_all(t, &at, all.as_mut_ptr(), capacity) };
        let want = if capacity < 8 { NepheleStatus::BadArgument } else if !valid { NepheleStatus::BadPoint } else { NepheleStatus::Ok };
        prop_assert_eq!(s, want);
        let mut o1 = 0.0;
        let s = unsafe { nephele_order1(t, &at, &mut o1) };
        prop_assert_eq!(s, if valid { NepheleStatus::Ok } else { NepheleStatus::BadPoint });
        prop_assert!(o1.is_finite(), "{at:?} → order 1 {o1}");
    }

    #[test]
    fn any_phase_parameters_get_a_status(
        a in any_f32(), b in any_f32(), c in any_f32(), d in any_f32(), x in any_f32(),
        model in 0usize..8,
    ) {
        let mut ph = std::ptr::null_mut();
        let s = unsafe {
            match model {
                0 => nephele_phase_hg(a, &mut ph),
                1 => nephele_phase_draine(a, b, &mut ph),
                2 => nephele_phase_hg_draine(a, b, c, d, &mut ph),
                3 => nephele_phase_hg_draine_diameter(a as f64, &mut ph),
                4 => nephele_phase_two_term_hg(a, b, c, &mut ph),
                5 => nephele_phase_rayleigh(&mut ph),
                6 => nephele_phase_schlick(a, &mut ph),
                _ => nephele_phase_vmf(a, &mut ph),
            }
        };
        prop_assert!(s == NepheleStatus::Ok || s == NepheleStatus::BadArgument, "{s:?}");
        prop_assert_eq!(ph.is_null(), s != NepheleStatus::Ok);
        if !ph.is_null() {
            let mut v = 0.0;
            for s in unsafe {
                [
                    nephele_phase_eval(ph, x, &mut v),
                    nephele_phase_pdf(ph, x, &mut v),
                    nephele_phase_sample(ph, x, &mut v),
                ]
            } {
                prop_assert!(s == NepheleStatus::Ok || s == NepheleStatus::BadArgument, "{s:?}");
                if s == NepheleStatus::Ok {
                    prop_assert!(v.is_finite(), "model {model} ({a}, {b}, {c}, {d}) at {x}: {v}");
                }
            }
        }
        unsafe { nephele_phase_free(ph) };
    }

    #[test]
    fn any_table_gets_a_status(
        steps in proptest::collection::vec(any_f32(), 0..40),
        values in proptest::collection::vec(any_f32(), 0..40),
        x in any_f32(),
        ordered in any::<bool>(),
    ) {
        // Either the caller's numbers as they come, or increasing angles ending at 180°.
        let mut theta: Vec<f64> = steps.iter().map(|&v| v as f64).collect();
        if ordered && theta.len() >= 2 {
            let n = theta.len();
            theta = (0..n).map(|i| 180.0 * i as f64 / (n - 1) as f64).collect();
        }
        let p: Vec<f64> = values.iter().take(theta.len()).map(|&v| v as f64).collect();
        let mut ph = std::ptr::null_mut();
        let s = unsafe { nephele_phase_tabulated(theta.as_ptr(), p.as_ptr(), p.len(), &mut ph) };
        prop_assert!(s == NepheleStatus::Ok || s == NepheleStatus::BadArgument, "{s:?}");
        if !ph.is_null() {
            let (mut v, mut mu) = (0.0, 0.0);
            let x = if x.is_nan() { 0.5 } else { x };
            let e = unsafe { nephele_phase_eval(ph, x.clamp(-1.0, 1.0), &mut v) };
            let m = unsafe { nephele_phase_sample(ph, x.clamp(0.0, 0.999), &mut mu) };
            prop_assert!(e == NepheleStatus::Ok && m == NepheleStatus::Ok);
            prop_assert!(v.is_finite() && mu.is_finite(), "{theta:?} {p:?}: {v} {mu}");
        }
        unsafe { nephele_phase_free(ph) };
    }

    #[test]
    fn any_search_gets_a_status(
        position in prop::array::uniform3(any_f32()),
        view in prop::array::uniform3(-1.0f32..1.0),
        sun in prop::array::uniform3(-1.0f32..1.0),
        scale in any_f32(),
        reads in 0u32..20,
        group in 0usize..10,
        sun_depth in prop_oneof![Just(f32::INFINITY), 0.0f32..100.0, any_f32()],
    ) {
        let t = tables().0;
        let unit = |v: [f32; 3]| {
            let n = v.iter().map(|x| x * x).sum::<f32>().sqrt();
            if n > 0.1 { v.map(|x| x / n) } else { v }
        };
        let surface = NepheleLitSurface {
            user: std::ptr::null_mut(),
            filtered: Some(sphere),
            lateral: None,
            sun_depth: Some(sphere_sun_depth),
            initial_scale: scale,
        };
        let v = NepheleViewpoint { position, view: unit(view), behind_min: 0.0, behind_max: f32::INFINITY, sun_depth };
        let mut opts = NepheleSearchOptions::default();
        unsafe { nephele_search_options_for_tables(t, &mut opts) };
        opts.max_reads = reads;
        let sun = unit(sun);
        let mut out = NepheleCollector::default();
        let s = unsafe { nephele_find_collector(t, group, &surface, &v, &sun, &opts, &mut out) };
        prop_assert!(
            matches!(s, NepheleStatus::Ok | NepheleStatus::BadArgument | NepheleStatus::BadGroup),
            "{s:?}"
        );
        if s == NepheleStatus::Ok && out.found == 1 {
            let tr = out.transport;
            prop_assert!(finite(&[tr.t, tr.c_x, tr.c_z, tr.sigma, out.sigma]), "{out:?}");
            let mut f = NepheleFiniteCloud::default();
            unsafe { nephele_finite_cloud_for_tables(t, &mut f) };
            let mut kept = NepheleKept::default();
            let k = unsafe { nephele_finite_cloud(t, group, &surface, &out, &f, &mut kept) };
            prop_assert_eq!(k, NepheleStatus::Ok);
            prop_assert!(kept.factor >= 0.0 && kept.factor <= 1.0, "{kept:?}");
        }
    }
}
