//! The collector search through the C ABI: the renderer's lit surface as C callbacks
//! ([`NepheleLitSurface`]), the search of one group or of all ([`nephele_find_collector`],
//! [`nephele_find_collectors`]) and the finite-cloud correction ([`nephele_finite_cloud`]),
//! each the runtime's function of the same name, bit for bit.

use crate::{fail, get, get_mut, guarded, slab_point_of, transport, NepheleSlabPoint};
use crate::{NepheleStatus, NepheleTables, NepheleTransport, NEPHELE_MAX_GROUPS};
use nephele_runtime::transport::{
    find_collector, find_collectors, finite_cloud, Collector, FilteredSurface, FiniteCloud,
    Lateral, LitSurface, SearchOptions, Viewpoint,
};
use std::ffi::c_void;

/// The lit surface filtered at one place and scale (what `filtered` writes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NepheleFilteredSurface {
    /// The filtered lit face's point on the light line of the query (m, world).
    pub entry: [f32; 3],
    /// Its outward unit normal (toward the sun's side).
    pub normal: [f32; 3],
    /// Geometric length of the chord from the lit face to the far face along the light (m).
    pub length: f32,
    /// Optical length of the same chord (mean free paths).
    pub optical_length: f32,
}

/// The cloud's cross-section across the light around a point, filtered (what `lateral`
/// writes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NepheleLateral {
    /// The share of the footprint the cloud covers, in [0, 1].
    pub coverage: f32,
    /// The mean distance across the light to the cross-section's edge over the covered part
    /// of the footprint (m).
    pub edge_distance: f32,
}

/// The renderer's cloud seen from the sun, as callbacks. Each returns 1 and writes `*out`
/// where the cloud covers the light line through `at` (m, world), 0 where it does not; they
/// are called from the searching thread only, and must not unwind.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct NepheleLitSurface {
    /// Passed back to the callbacks.
    pub user: *mut c_void,
    /// The surface filtered at scale `sigma` (m) around the light line through `at`.
    pub filtered: Option<
        unsafe extern "C" fn(
            user: *mut c_void,
            at: *const f32,
            sigma: f32,
            out: *mut NepheleFilteredSurface,
        ) -> i32,
    >,
    /// The cross-section filtered at `sigma` around the light line through `at`, for the
    /// finite-cloud correction; null: the surface knows no edge (an unbounded slab).
    pub lateral: Option<
        unsafe extern "C" fn(
            user: *mut c_void,
            at: *const f32,
            sigma: f32,
            out: *mut NepheleLateral,
        ) -> i32,
    >,
    /// The sun's optical depth (mean free paths) to `at` through the cloud as it is, into
    /// `*out` (1; 0 where unknown), which the search averages across the light over each
    /// group's spread (`NepheleSearchOptions::sun_spread`); null: unknown everywhere.
    pub sun_depth:
        Option<unsafe extern "C" fn(user: *mut c_void, at: *const f32, out: *mut f32) -> i32>,
    /// σ₀ (m, > 0): the scale of the first filtering, the cloud's size.
    pub initial_scale: f32,
}

/// Where the light is seen: p (m, world), the direction the light travels toward the eye
/// (unit), the optical depth (mean free paths) the view ray holds beyond p, at least
/// `behind_min` and at most `behind_max` (infinity when unknown), and p's optical depth to the
/// sun through the cloud as it is, `sun_depth` (infinity when unknown).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NepheleViewpoint {
    pub position: [f32; 3],
    pub view: [f32; 3],
    pub behind_min: f32,
    pub behind_max: f32,
    pub sun_depth: f32,
}

/// The search's settings (`nephele_search_options_default` gives the runtime's default,
/// `nephele_search_options_for_tables` the one for a set of tables): most table reads, the
/// tolerance ε (converged when the collector moves less than ε σ across the light and σ
/// changes by less than ε σ), the step clamp and the filtering at σ (1 on, 0 off), and
/// whether each group reads p's depth to the sun averaged across the light over its walks'
/// spread (`sun_spread` 1, for a phase function of mean cosine `mean_cosine` in (−1, 1); 0:
/// p's own depth for every group).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NepheleSearchOptions {
    pub max_reads: u32,
    pub tolerance: f32,
    pub step_clamp: i32,
    pub filter: i32,
    pub sun_spread: i32,
    pub mean_cosine: f32,
}

impl NepheleSearchOptions {
    fn of(d: &SearchOptions) -> Self {
        Self {
            max_reads: d.max_reads,
            tolerance: d.tolerance,
            step_clamp: i32::from(d.step_clamp),
            filter: i32::from(d.filter),
            sun_spread: i32::from(d.sun_spread.is_some()),
            mean_cosine: d.sun_spread.unwrap_or(0.0),
        }
    }
}

/// Which finite-cloud corrections apply and the medium's constants
/// (`nephele_finite_cloud_for_tables` gives lateral leakage from diffusion theory with no
/// fitted constant, for the tables' phase function).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NepheleFiniteCloud {
    /// Lateral leakage through the cloud's sides (1 on, 0 off).
    pub leakage: i32,
    /// T weighed by the share of the collector's footprint the cloud covers (1 on, 0 off).
    pub coverage: i32,
    /// κ⊥ times this (1: diffusion theory as is).
    pub rate_scale: f32,
    /// The sides count from order n_c = this × (δ̄ + z_e)²/D on.
    pub delay_scale: f32,
    /// The sides count a path's orders by how far the walk has spread across the light (1,
    /// the default), or order by order from the first (0).
    pub spread: i32,
    /// κ_a = −ln ϖ per scattering (0 for water clouds in the visible).
    pub absorption: f32,
    /// g, the phase function's mean cosine.
    pub mean_cosine: f32,
}

/// One group's search: `found` 0 where the surface has no cloud on the light line through p
/// or the tables hold no light there (the rest 0); else T, c and σ of the last read, the slab
/// it was read at, the collector's centre on the filtered lit face (m, world) and spread σ
/// (m), the reads, whether it converged (1) before the cap, the parameters held at the
/// tables' domain (bits: 1 thickness, 2 μ_L, 4 depth, 8 view, 16 the slab cut or grown to p's
/// depth to the sun) and κ̄ (1/m).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NepheleCollector {
    pub found: i32,
    pub transport: NepheleTransport,
    pub at: NepheleSlabPoint,
    pub centre: [f32; 3],
    pub sigma: f32,
    pub reads: u32,
    pub converged: i32,
    pub clamps: u32,
    pub extinction: f32,
}

/// What one group's collector keeps of T: the factor in [0, 1], the lateral radius R it used
/// (mean free paths; infinity where the surface knows no edge) and the footprint's coverage.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NepheleKept {
    pub factor: f32,
    pub radius: f32,
    pub coverage: f32,
}

/// The C callbacks as the runtime's [`LitSurface`].
struct CSurface(NepheleLitSurface);

impl LitSurface for CSurface {
    fn filtered(&self, at: [f32; 3], sigma: f32) -> Option<FilteredSurface> {
        let f = self.0.filtered?;
        let mut out = NepheleFilteredSurface::default();
        // SAFETY: the caller promised a callback valid for these arguments.
        let hit = unsafe { f(self.0.user, at.as_ptr(), sigma, &mut out) };
        (hit != 0).then_some(FilteredSurface {
            entry: out.entry,
            normal: out.normal,
            length: out.length,
            optical_length: out.optical_length,
        })
    }

    fn initial_scale(&self) -> f32 {
        self.0.initial_scale
    }

    fn lateral(&self, at: [f32; 3], sigma: f32) -> Option<Lateral> {
        let f = self.0.lateral?;
        let mut out = NepheleLateral::default();
        // SAFETY: as `filtered`.
        let hit = unsafe { f(self.0.user, at.as_ptr(), sigma, &mut out) };
        (hit != 0).then_some(Lateral {
            coverage: out.coverage,
            edge_distance: out.edge_distance,
        })
    }

    fn sun_depth(&self, at: [f32; 3]) -> Option<f32> {
        let f = self.0.sun_depth?;
        let mut out = 0.0f32;
        // SAFETY: as `filtered`.
        let known = unsafe { f(self.0.user, at.as_ptr(), &mut out) };
        (known != 0).then_some(out)
    }
}

/// The runtime's search, checked: a `filtered` callback, σ₀ > 0, p finite, a unit view and a
/// unit sun (within 1e-3), at least one read and ε ≥ 0.
fn search_inputs(
    surface: &NepheleLitSurface,
    v: &NepheleViewpoint,
    sun: &[f32; 3],
    opts: &NepheleSearchOptions,
) -> Result<(CSurface, Viewpoint, SearchOptions), NepheleStatus> {
    let bad = |what: &str| Err(fail(NepheleStatus::BadArgument, what));
    if surface.filtered.is_none() {
        return Err(fail(NepheleStatus::NullPointer, "surface.filtered is null"));
    }
    let unit = |a: &[f32; 3]| {
        let n = a.iter().map(|x| x * x).sum::<f32>();
        (n - 1.0).abs() <= 1e-3
    };
    if !(surface.initial_scale > 0.0 && surface.initial_scale.is_finite()) {
        return bad("surface.initial_scale: a length > 0 (m)");
    }
    if !v.position.iter().all(|x| x.is_finite()) || !unit(&v.view) || !unit(sun) {
        return bad("viewpoint.position finite, viewpoint.view and sun unit vectors");
    }
    if opts.max_reads == 0
        || !(opts.tolerance >= 0.0)
        || !(v.behind_min >= 0.0)
        || !(v.sun_depth >= 0.0)
        || (opts.sun_spread != 0 && !(opts.mean_cosine.abs() < 1.0))
    {
        return bad(
            "options.max_reads ≥ 1, options.tolerance ≥ 0, options.mean_cosine in (−1, 1) \
             with options.sun_spread, viewpoint.behind_min ≥ 0, viewpoint.sun_depth ≥ 0",
        );
    }
    Ok((
        CSurface(*surface),
        Viewpoint {
            position: v.position,
            view: v.view,
            behind_min: v.behind_min,
            behind_max: v.behind_max,
            sun_depth: v.sun_depth,
        },
        SearchOptions {
            max_reads: opts.max_reads,
            tolerance: opts.tolerance,
            step_clamp: opts.step_clamp != 0,
            filter: opts.filter != 0,
            sun_spread: (opts.sun_spread != 0).then_some(opts.mean_cosine),
        },
    ))
}

fn collector(c: Option<Collector>) -> NepheleCollector {
    let Some(c) = c else {
        return NepheleCollector::default();
    };
    let bit = |on: bool, b: u32| if on { b } else { 0 };
    NepheleCollector {
        found: 1,
        transport: transport(&c.transport),
        at: slab_point_of(&c.at),
        centre: c.centre,
        sigma: c.sigma,
        reads: c.reads,
        converged: i32::from(c.converged),
        clamps: bit(c.clamps.thickness, 1)
            | bit(c.clamps.mu_l, 2)
            | bit(c.clamps.depth, 4)
            | bit(c.clamps.view, 8)
            | bit(c.clamps.sun, 16),
        extinction: c.extinction,
    }
}

/// The runtime's default search settings into `*out`.
///
/// # Safety
/// `out` is valid for writes (or null).
#[no_mangle]
pub unsafe extern "C" fn nephele_search_options_default(
    out: *mut NepheleSearchOptions,
) -> NepheleStatus {
    guarded(|| match unsafe { get_mut(out, "out") } {
        Ok(o) => {
            *o = NepheleSearchOptions::of(&SearchOptions::default());
            NepheleStatus::Ok
        }
        Err(s) => s,
    })
}

/// The search settings for `tables` into `*out`: the runtime's default with each group's
/// sun depth spread by the tables' phase function.
///
/// # Safety
/// `tables` is a valid handle (or null); `out` is valid for writes (or null).
#[no_mangle]
pub unsafe extern "C" fn nephele_search_options_for_tables(
    tables: *const NepheleTables,
    out: *mut NepheleSearchOptions,
) -> NepheleStatus {
    unsafe {
        crate::from_tables(tables, out, |t| {
            NepheleSearchOptions::of(&SearchOptions::for_tables(t))
        })
    }
}

/// The collector of `group` seen from `*viewpoint`, the sun toward `sun` (unit, 3 floats), on
/// the renderer's `*surface`, into `*out` (`found` 0 where there is none).
///
/// # Safety
/// The pointers are valid (or null; `sun` for 3 reads); the callbacks are valid for the
/// arguments the runtime passes (a point of 3 floats, a scale, an output), and neither free
/// the tables nor write the outputs of the call they are called from.
#[no_mangle]
pub unsafe extern "C" fn nephele_find_collector(
    tables: *const NepheleTables,
    group: usize,
    surface: *const NepheleLitSurface,
    viewpoint: *const NepheleViewpoint,
    sun: *const [f32; 3],
    options: *const NepheleSearchOptions,
    out: *mut NepheleCollector,
) -> NepheleStatus {
    guarded(|| {
        done(|| {
            let t = unsafe { get(tables, "tables")? };
            let (s, v) = unsafe { (get(surface, "surface")?, get(viewpoint, "viewpoint")?) };
            let (sun, o) = unsafe { (get(sun, "sun")?, get(options, "options")?) };
            // Checked now, written after the search: no reference to `out` is alive while the
            // caller's callbacks run (they may reach that memory through `user`).
            unsafe { get_mut(out, "out")? };
            if group >= t.tables().groups() {
                return Err(crate::bad_group(group, t));
            }
            let (surface, v, opts) = search_inputs(s, v, sun, o)?;
            let found = collector(find_collector(t.tables(), group, &surface, &v, *sun, &opts));
            *unsafe { get_mut(out, "out")? } = found;
            Ok(())
        })
    })
}

/// The collectors of every group (as `nephele_find_collector` gives each, bit for bit, with
/// the first read shared) into `out[0 .. groups)` (`capacity` ≥ the group count).
///
/// # Safety
/// As `nephele_find_collector`; `out` is valid for `capacity` writes.
#[no_mangle]
pub unsafe extern "C" fn nephele_find_collectors(
    tables: *const NepheleTables,
    surface: *const NepheleLitSurface,
    viewpoint: *const NepheleViewpoint,
    sun: *const [f32; 3],
    options: *const NepheleSearchOptions,
    out: *mut NepheleCollector,
    capacity: usize,
) -> NepheleStatus {
    guarded(|| {
        done(|| {
            let t = unsafe { get(tables, "tables")? };
            let (s, v) = unsafe { (get(surface, "surface")?, get(viewpoint, "viewpoint")?) };
            let (sun, o) = unsafe { (get(sun, "sun")?, get(options, "options")?) };
            // Checked now, written after the search (as in `nephele_find_collector`).
            let groups = unsafe { crate::group_slice(t, (out, capacity))? }.len();
            let (surface, v, opts) = search_inputs(s, v, sun, o)?;
            let mut all = [None; NEPHELE_MAX_GROUPS];
            find_collectors(t.tables(), &surface, &v, *sun, &opts, &mut all[..groups]);
            let out = unsafe { crate::group_slice(t, (out, capacity))? };
            for (o, c) in out.iter_mut().zip(all) {
                *o = collector(c);
            }
            Ok(())
        })
    })
}

/// `NEPHELE_STATUS_OK` or the error of `f`.
fn done(f: impl FnOnce() -> Result<(), NepheleStatus>) -> NepheleStatus {
    f().err().unwrap_or(NepheleStatus::Ok)
}

/// Lateral leakage from diffusion theory, no fitted constant, for the tables' phase function,
/// into `*out`.
///
/// # Safety
/// The pointers are valid (or null).
#[no_mangle]
pub unsafe extern "C" fn nephele_finite_cloud_for_tables(
    tables: *const NepheleTables,
    out: *mut NepheleFiniteCloud,
) -> NepheleStatus {
    unsafe {
        crate::from_tables(tables, out, |t| {
            let f = FiniteCloud::for_tables(t);
            NepheleFiniteCloud {
                leakage: i32::from(f.leakage),
                coverage: i32::from(f.coverage),
                rate_scale: f.rate_scale,
                delay_scale: f.delay_scale,
                spread: i32::from(f.spread),
                absorption: f.absorption,
                mean_cosine: f.mean_cosine,
            }
        })
    }
}

/// The share of `group`'s T the cloud keeps at the collector `*found` (from
/// `nephele_find_collector` on the same surface; `found` = 1) into `*out`. Only the surface's
/// `lateral` callback is called (none: the surface knows no edge).
///
/// # Safety
/// As `nephele_find_collector`.
#[no_mangle]
pub unsafe extern "C" fn nephele_finite_cloud(
    tables: *const NepheleTables,
    group: usize,
    surface: *const NepheleLitSurface,
    found: *const NepheleCollector,
    finite: *const NepheleFiniteCloud,
    out: *mut NepheleKept,
) -> NepheleStatus {
    guarded(|| {
        done(|| {
            let t = unsafe { get(tables, "tables")? };
            let (s, c) = unsafe { (get(surface, "surface")?, get(found, "found")?) };
            let f = unsafe { get(finite, "finite")? };
            unsafe { get_mut(out, "out")? };
            if group >= t.tables().groups() {
                return Err(crate::bad_group(group, t));
            }
            if c.found == 0 {
                return Err(fail(
                    NepheleStatus::BadArgument,
                    "found: no collector (found = 0)",
                ));
            }
            let collector = Collector {
                transport: nephele_runtime::transport::Transport {
                    t: c.transport.t,
                    c_x: c.transport.c_x,
                    c_z: c.transport.c_z,
                    sigma: c.transport.sigma,
                },
                at: crate::slab_point(&c.at),
                unheld: nephele_runtime::transport::Unheld {
                    thickness: c.at.thickness,
                    mu_l: c.at.mu_l,
                },
                centre: c.centre,
                sigma: c.sigma,
                reads: c.reads,
                converged: c.converged != 0,
                clamps: nephele_runtime::transport::Clamps {
                    thickness: c.clamps & 1 != 0,
                    mu_l: c.clamps & 2 != 0,
                    depth: c.clamps & 4 != 0,
                    view: c.clamps & 8 != 0,
                    sun: c.clamps & 16 != 0,
                },
                extinction: c.extinction,
            };
            let finite = FiniteCloud {
                leakage: f.leakage != 0,
                coverage: f.coverage != 0,
                rate_scale: f.rate_scale,
                delay_scale: f.delay_scale,
                spread: f.spread != 0,
                absorption: f.absorption,
                mean_cosine: f.mean_cosine,
            };
            let k = finite_cloud(t.tables(), group, &CSurface(*s), &collector, &finite);
            *unsafe { get_mut(out, "out")? } = NepheleKept {
                factor: k.factor,
                radius: k.radius,
                coverage: k.coverage,
            };
            Ok(())
        })
    })
}
