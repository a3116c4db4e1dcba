//! The collector search of Bouthors et al. 2008, §6.1: where, on a cloud's lit surface, the
//! light of one order group seen at a point p enters, found as a fixed point on (c, σ).
//!
//! The cloud is treated, around the collector, as the slab tangent to its lit surface filtered
//! at the collector's own size σ (a scale-dependent orientation: light entering over a wide
//! collector sees the surface's large shape, not its bumps). Given p (m, world) and the view
//! (ω_V, the direction the light travels toward the eye) one group's search is
//!
//!   c₀ = p, σ₀ = [`LitSurface::initial_scale`];
//!   step i ≥ 1: S = the surface filtered at σ_{i−1} on the light line through c_{i−1};
//!               the local slab (d, t, μ_V, ψ_V, μ_L) of p under S ([`local_slab`]);
//!               (c, σ) from the tables there, c mapped to the world on S's lit face: (c_i, σ_i);
//!               |c_i − c_{i−1}|⊥ ≤ σ_i (the step clamp, from step 2 on: c₀ is a guess, not a
//!               candidate, and the clamp is there to stop a 2-cycle between candidates);
//!   stop after step i when the move across the light, |c_i − c_{i−1}|⊥, and |σ_i − σ_{i−1}|
//!   are both ≤ ε σ_i (converged), or after N steps (the cap);
//!   T = the tables' T with the arguments of the last step.
//!
//! Moves are measured across the light (⊥ ω_L) because the surface is a height field seen
//! from the sun: a point is as good as its light line. The iteration count is the number of
//! table reads: on a plane the first read is already the slab's own answer and the second
//! confirms it (2 reads); a search that never settles stops at N.
//!
//! Units: positions in metres; the tables speak mean free paths, and the surface gives, with
//! each filtered sample, the optical length of its light chord (mfp) beside the geometric one
//! (m): their ratio κ̄ (1/m, the chord's mean extinction) converts. With optical rather than
//! geometric thickness a heterogeneous interior (voxel clouds, the fBm boundary layer) gets the
//! slab it actually has along the light.

use super::format::MAX_GROUPS;
use super::geometry::SlabPoint;
use super::sun_depth::group_viewpoint;
use super::surface::{
    Clamps, Collector, FilteredSurface, LitSurface, LocalSlab, SearchOptions, Unheld, Viewpoint,
};
use super::tables::{Transport, TransportTables};
use crate::frame::{cross, dot, Vec3};
use crate::real::{Math, Real};

fn add(a: Vec3<f32>, b: Vec3<f32>, s: f32) -> Vec3<f32> {
    [a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]]
}

fn length(a: Vec3<f32>) -> f32 {
    dot(a, a).sqrt()
}

/// The angle in [0, π] between two vectors given its cosine and sine (≥ 0) up to a common
/// positive factor (atan2 from asin, the runtime's math).
fn angle_of(cos: f32, sin: f32) -> f32 {
    let r = (cos * cos + sin * sin).sqrt();
    if r <= 0.0 {
        return 0.0;
    }
    if sin < cos.abs() {
        let a = (sin / r).asin();
        if cos >= 0.0 {
            a
        } else {
            f32::PI - a
        }
    } else {
        0.5 * f32::PI - (cos / r).asin()
    }
}

/// The slab tangent to `s` that holds the viewpoint `v` with the sun toward `sun` (unit):
/// μ_L = n̄·ω_L, d = κ̄ (entry − p)·n̄, μ_V = ω_V·n̄, ψ_V the angle between the horizontal parts
/// of the beam's travel (−ω_L) and of ω_V, and t = max(τ_chord μ_L, d + μ_V⁺ behind_min): the
/// chord crosses the slab obliquely, and the slab holds p and, seen going up, the medium the
/// view ray holds beyond p, below it. t and μ_L are held within `tables`' domain, d within
/// [0, t] (each flagged). Then d is held where the slab's path beyond p along −ω_V —
/// (t − d)/μ_V for μ_V > 0, d/|μ_V| for μ_V < 0 — lies within the view ray's own
/// [behind_min, behind_max] (flagged `view`): the radiance at p toward the eye is scattered by
/// the medium behind p, and a slab fitted to the light alone may have far more there than the
/// cloud (a thin wisp, a grazing ray) or, seen going down, less. Last, seen going up, p lies
/// no deeper than its own depth to the sun, d_☉ = μ_L τ_☉ (`v.sun_depth`): where d > d_☉ the
/// slab above p is cut to it, d = d_☉ and t = d_☉ + (t − d), the medium below p kept; and
/// where d_☉ > t, whatever the view, the slab grows at its lit face by d_☉ − t, and p with it
/// (both flagged `sun`).
pub fn local_slab(
    tables: &TransportTables,
    s: &FilteredSurface,
    v: &Viewpoint,
    sun: Vec3<f32>,
) -> LocalSlab {
    let (p, view) = (v.position, v.view);
    let domain = tables.domain();
    let n = s.normal;
    let mut clamps = Clamps::default();
    let mu_l_raw = dot(n, sun);
    let mu_l = mu_l_raw.clamp_to(domain.mu_l.0, domain.mu_l.1);
    clamps.mu_l = mu_l != mu_l_raw;
    let extinction = extinction_of(s);
    let below = dot([s.entry[0] - p[0], s.entry[1] - p[1], s.entry[2] - p[2]], n);
    let d_raw = extinction * below;
    let mu_v = dot(view, n).clamp_to(-1.0, 1.0);
    // The slab holds the viewpoint: at least as thick as p lies deep. The chord at the
    // filtered surface can be shorter than the medium above p (a cloud lit from behind, p on
    // its far face): read at its far face, the slab would hand p the light of a thinner cloud
    // (docs/collector.md, "cloud_behind"). Seen going up, it holds the view ray's medium
    // beyond p below p too, rather than lift p toward the light for it, which would hand a
    // shadowed face the light of the lit one (docs/collector.md, "Shadowed faces and
    // silhouettes").
    let held = if mu_v > 0.0 {
        d_raw + mu_v * v.behind_min
    } else {
        d_raw
    };
    // t held within the tables' thicknesses, flagged, the value before kept.
    let mut unheld = Unheld {
        thickness: 0.0,
        mu_l: mu_l_raw,
    };
    let hold_thickness = |t: f32, clamps: &mut Clamps, unheld: &mut Unheld| {
        let h = t.clamp_to(domain.thickness.0, domain.thickness.1);
        clamps.thickness |= h != t;
        // The farthest the slab reached: the later steps start from a held t.
        unheld.thickness = unheld.thickness.max(t);
        h
    };
    let thickness = hold_thickness(
        (s.optical_length * mu_l).max(held),
        &mut clamps,
        &mut unheld,
    );
    let depth = d_raw.clamp_to(0.0, thickness);
    clamps.depth = depth != d_raw;
    let (lo, hi) = if mu_v > 0.0 {
        (
            thickness - mu_v * v.behind_max,
            thickness - mu_v * v.behind_min,
        )
    } else if mu_v < 0.0 {
        (-mu_v * v.behind_min, -mu_v * v.behind_max)
    } else {
        (0.0, thickness)
    };
    let (lo, hi) = (lo.clamp_to(0.0, thickness), hi.clamp_to(0.0, thickness));
    let depth_v = depth.clamp_to(lo, hi.max(lo));
    clamps.view = depth_v != depth;
    // p lies no deeper than the sun's own path to it: the plane under a filtered face puts a
    // cloud's sunlit edge, which a grazing ray sees, at the far face of a thick slab, whose
    // light has crossed all of it, while the sun reaches p through μ_L τ_☉
    // (docs/collector.md, "Shadowed faces and silhouettes").
    // And where the slab is thinner than p's depth to the sun, the light has crossed more cloud
    // to reach p than the slab holds (a cloud lit from behind, seen through its thinner lower
    // part): the slab grows at its lit face by what it lacks, p as far from its far face as
    // before (docs/collector.md, "The sun's depth, spread across the light").
    let d_sun = mu_l * v.sun_depth;
    let (depth, thickness) = if mu_v > 0.0 && depth_v > d_sun {
        clamps.sun = true;
        let t = hold_thickness(d_sun + (thickness - depth_v), &mut clamps, &mut unheld);
        (d_sun.min(t), t)
    } else if d_sun.is_finite() && d_sun > thickness {
        clamps.sun = true;
        let excess = d_sun - thickness;
        let t = hold_thickness(thickness + excess, &mut clamps, &mut unheld);
        ((depth_v + excess).min(t), t)
    } else {
        (depth_v, thickness)
    };
    // Horizontal parts (⊥ n̄) of the beam's travel and of the view.
    let beam_h = add([-sun[0], -sun[1], -sun[2]], n, mu_l_raw);
    let view_h = add(view, n, -mu_v);
    let (bl, vl) = (length(beam_h), length(view_h));
    let z_axis = if bl > 1e-6 {
        beam_h.map(|x| x / bl)
    } else if vl > 1e-6 {
        // Sun along the normal: ψ_V is the view's own azimuth, 0 (c turns with the view).
        view_h.map(|x| x / vl)
    } else {
        any_perpendicular(n)
    };
    let cos_psi = dot(view_h, z_axis);
    let across = add(view_h, z_axis, -cos_psi);
    let al = length(across);
    let x_axis = if al > 1e-6 * vl.max(1e-30) && al > 0.0 {
        across.map(|x| x / al)
    } else {
        cross(n, z_axis)
    };
    LocalSlab {
        at: SlabPoint {
            depth,
            thickness,
            mu_v,
            psi_v: angle_of(cos_psi, al),
            mu_l,
        },
        clamps,
        unheld,
        foot: add(p, n, below),
        z_axis,
        x_axis,
        extinction,
    }
}

fn any_perpendicular(n: Vec3<f32>) -> Vec3<f32> {
    let (t, _) = crate::frame::orthonormal_basis(n);
    t
}

/// The collector of group `g` for the viewpoint `v`, the sun toward `sun` (unit): the fixed
/// point of the module's doc. None where the surface has no cloud on the light line through p, or where the tables
/// hold no light or no collector for this group there; a later step that finds no cloud (or
/// no light) ends the search with the step before it (not converged).
pub fn find_collector<S: LitSurface + ?Sized>(
    tables: &TransportTables,
    g: usize,
    surface: &S,
    v: &Viewpoint,
    sun: Vec3<f32>,
    opts: &SearchOptions,
) -> Option<Collector> {
    let start = Search::new(v, surface);
    let s = start.first_surface(surface, opts)?;
    let v = group_viewpoint(tables, g, surface, v, sun, extinction_of(&s), opts);
    let slab = local_slab(tables, &s, &v, sun);
    let first = tables.evaluate(g, &slab.read_at());
    start.continue_after(first, &slab, tables, g, (surface, &v, sun), opts)
}

/// The collectors of every group for the viewpoint `v` into `out[..groups()]` (each as
/// [`find_collector`] gives it, bit for bit; the rest of `out` untouched). The first step is
/// the same for every group — the surface filtered at the map's extent around p — so it reads
/// the tables once for all of them ([`TransportTables::evaluate_all`], which shares the
/// features); each group then searches on alone.
pub fn find_collectors<S: LitSurface + ?Sized>(
    tables: &TransportTables,
    surface: &S,
    v: &Viewpoint,
    sun: Vec3<f32>,
    opts: &SearchOptions,
    out: &mut [Option<Collector>],
) {
    let groups = tables.groups().min(out.len()).min(MAX_GROUPS);
    out[..groups].iter_mut().for_each(|o| *o = None);
    if groups == 0 {
        return;
    }
    let start = Search::new(v, surface);
    let Some(s) = start.first_surface(surface, opts) else {
        return;
    };
    let extinction = extinction_of(&s);
    let views: [Viewpoint; MAX_GROUPS] = core::array::from_fn(|g| {
        if g < groups {
            group_viewpoint(tables, g, surface, v, sun, extinction, opts)
        } else {
            *v
        }
    });
    let slabs: [LocalSlab; MAX_GROUPS] =
        core::array::from_fn(|g| local_slab(tables, &s, &views[g], sun));
    let mut first = [Transport::default(); MAX_GROUPS];
    // Groups whose spread sun depth cuts or grows the slab otherwise than the first group's
    // read their own alone (the same bits: one group of `evaluate_all` is `evaluate`'s).
    tables.evaluate_all(&slabs[0].read_at(), &mut first[..groups]);
    for (g, slot) in first[..groups].iter_mut().enumerate().skip(1) {
        if slabs[g].at != slabs[0].at {
            *slot = tables.evaluate(g, &slabs[g].read_at());
        }
    }
    for (g, slot) in out[..groups].iter_mut().enumerate() {
        *slot = start.continue_after(
            first[g],
            &slabs[g],
            tables,
            g,
            (surface, &views[g], sun),
            opts,
        );
    }
}

/// κ̄ (1/m) of a filtered surface's chord: its optical over its geometric length (0 for none).
fn extinction_of(s: &FilteredSurface) -> f32 {
    if s.length > 0.0 {
        s.optical_length / s.length
    } else {
        0.0
    }
}

/// A search in progress: the current collector centre and spread, the last step's result and
/// the reads so far.
#[derive(Clone, Copy)]
struct Search {
    c: Vec3<f32>,
    sigma: f32,
    last: Option<Collector>,
    reads: u32,
}

/// What a step decided.
enum Step {
    /// The search ends with this result.
    Done(Option<Collector>),
    /// Another read is needed.
    Next,
}

impl Search {
    /// The start: c₀ = p, σ₀ = the surface's extent.
    fn new<S: LitSurface + ?Sized>(v: &Viewpoint, surface: &S) -> Self {
        Self {
            c: v.position,
            sigma: surface.initial_scale(),
            last: None,
            reads: 0,
        }
    }

    /// The surface filtered at σ₀ around p: the first step's, the same for every group (None:
    /// no cloud on p's light line).
    fn first_surface<S: LitSurface + ?Sized>(
        &self,
        surface: &S,
        opts: &SearchOptions,
    ) -> Option<FilteredSurface> {
        let scale = if opts.filter { self.sigma } else { 0.0 };
        query(surface, self.c, scale, None)
    }

    /// The search of group `g` from its first read `first` in the slab `slab` on to its end.
    fn continue_after<S: LitSurface + ?Sized>(
        mut self,
        first: Transport,
        slab: &LocalSlab,
        tables: &TransportTables,
        g: usize,
        (surface, v, sun): (&S, &Viewpoint, Vec3<f32>),
        opts: &SearchOptions,
    ) -> Option<Collector> {
        match self.advance(first, slab, sun, opts) {
            Step::Done(c) => c,
            Step::Next => self.run(tables, g, (surface, v, sun), opts),
        }
    }

    /// Reads on until the search ends.
    fn run<S: LitSurface + ?Sized>(
        mut self,
        tables: &TransportTables,
        g: usize,
        (surface, v, sun): (&S, &Viewpoint, Vec3<f32>),
        opts: &SearchOptions,
    ) -> Option<Collector> {
        loop {
            let scale = if opts.filter { self.sigma } else { 0.0 };
            let Some(s) = query(surface, self.c, scale, self.last.as_ref()) else {
                return self.last;
            };
            let slab = local_slab(tables, &s, v, sun);
            let tr = tables.evaluate(g, &slab.read_at());
            if let Step::Done(c) = self.advance(tr, &slab, sun, opts) {
                return c;
            }
        }
    }

    /// One step from the read `tr` in the local slab `slab`: the new centre and spread.
    fn advance(
        &mut self,
        tr: Transport,
        slab: &LocalSlab,
        sun: Vec3<f32>,
        opts: &SearchOptions,
    ) -> Step {
        self.reads += 1;
        if !(tr.t > 0.0 && tr.sigma > 0.0 && slab.extinction > 0.0) {
            return Step::Done(self.last);
        }
        let k = 1.0 / slab.extinction;
        let target = add(
            add(slab.foot, slab.z_axis, tr.c_z * k),
            slab.x_axis,
            tr.c_x * k,
        );
        let new_sigma = tr.sigma * k;
        // The move across the light, clamped; along the light the point follows the target
        // (it stays on the lit face, where the collector is reported).
        let delta = [
            target[0] - self.c[0],
            target[1] - self.c[1],
            target[2] - self.c[2],
        ];
        let along = dot(delta, sun);
        let mut across = add(delta, sun, -along);
        let mut moved = length(across);
        if opts.step_clamp && self.reads > 1 && moved > new_sigma {
            across = across.map(|x| x * new_sigma / moved);
            moved = new_sigma;
        }
        let converged = self.reads > 1
            && moved <= opts.tolerance * new_sigma
            && (new_sigma - self.sigma).abs() <= opts.tolerance * new_sigma;
        self.c = add(add(self.c, across, 1.0), sun, along);
        self.sigma = new_sigma;
        let found = Collector {
            transport: tr,
            at: slab.at,
            centre: self.c,
            sigma: self.sigma,
            reads: self.reads,
            converged,
            clamps: slab.clamps,
            unheld: slab.unheld,
            extinction: slab.extinction,
        };
        if converged || self.reads >= opts.max_reads.max(1) {
            return Step::Done(Some(found));
        }
        self.last = Some(found);
        Step::Next
    }
}

/// The surface at `c`; where no cloud covers it (the collector was sent past the cloud's
/// edge), halfway back toward the previous collector, at most four times.
fn query<S: LitSurface + ?Sized>(
    surface: &S,
    mut c: Vec3<f32>,
    scale: f32,
    last: Option<&Collector>,
) -> Option<FilteredSurface> {
    for _ in 0..4 {
        if let Some(s) = surface.filtered(c, scale) {
            return Some(s);
        }
        let prev = last?.centre;
        c = [
            0.5 * (c[0] + prev[0]),
            0.5 * (c[1] + prev[1]),
            0.5 * (c[2] + prev[2]),
        ];
    }
    surface.filtered(c, scale)
}

#[cfg(all(test, feature = "std", feature = "embed"))]
mod tests {
    use super::*;

    /// An infinite plane slab: lit face z = h (normal +z), far face z = 0, extinction k.
    struct Plane {
        h: f32,
        k: f32,
    }

    impl LitSurface for Plane {
        fn filtered(&self, at: Vec3<f32>, _sigma: f32) -> Option<FilteredSurface> {
            Some(FilteredSurface {
                entry: [at[0], at[1], self.h],
                normal: [0.0, 0.0, 1.0],
                length: self.h,
                optical_length: self.h * self.k,
            })
        }
        fn initial_scale(&self) -> f32 {
            1e4
        }
    }

    fn unit(v: Vec3<f32>) -> Vec3<f32> {
        let l = length(v);
        v.map(|x| x / l)
    }

    #[test]
    fn angle_of_matches_atan2() {
        for i in 0..=64 {
            let a = i as f32 * core::f32::consts::PI / 64.0;
            for r in [1e-3f32, 1.0, 30.0] {
                let got = angle_of(r * a.cos(), r * a.sin());
                assert!((got - a).abs() < 2e-6, "{a}: {got}");
            }
        }
    }

    /// The plane's local slab is the slab itself (the light chord is t/μ_L long), so the first
    /// read is its own (c, σ, T) and the second confirms it; straight (ψ from geometry) checks.
    #[test]
    fn a_plane_returns_its_own_slab_in_one_step() {
        let tables = crate::embedded::mie_10um();
        let sun = unit([0.0, 0.6, 0.8]);
        let plane = Plane { h: 200.0, k: 0.05 };
        // Chord along the light: the plane's maps give the vertical thickness; convert.
        let surface = Chord(&plane, sun);
        for (p, view) in [
            ([10.0, -30.0, 150.0], unit([0.3, -0.2, 0.9])),
            ([0.0, 0.0, 20.0], unit([-0.5, 0.1, -0.8])),
            ([5.0, 5.0, 199.0], unit([0.9, 0.1, 0.2])),
        ] {
            let t = plane.h * plane.k;
            let d = (plane.h - p[2]) * plane.k;
            let mu_v = view[2];
            let (vx, vy) = (view[0], view[1]);
            // Beam's horizontal travel: −(0, 0.6) → +(0, −1) direction.
            let cos = -vy / (vx * vx + vy * vy).sqrt();
            let own = SlabPoint {
                depth: d,
                thickness: t,
                mu_v,
                psi_v: cos.acos(),
                mu_l: 0.8,
            };
            for g in 0..tables.groups() {
                let want = tables.evaluate(g, &own);
                let vp = Viewpoint::new(p, view);
                let got = find_collector(&tables, g, &surface, &vp, sun, &SearchOptions::default())
                    .expect("light on a plane");
                assert_eq!(got.reads, 2, "group {g}: reads");
                assert!(got.converged && !got.clamps.any());
                let rel = |a: f32, b: f32| (a - b).abs() <= 1e-4 * (1.0 + b.abs());
                assert!(rel(got.transport.t, want.t), "T {got:?} vs {want:?}");
                assert!(rel(got.transport.sigma, want.sigma), "σ");
                assert!(rel(got.transport.c_z, want.c_z) && rel(got.transport.c_x, want.c_x));
                // The centre: p's foot on the face plus c (mfp → m).
                let z = unit([0.0, -1.0, 0.0]);
                let x = [vx.signum(), 0.0, 0.0];
                let want_c = [
                    p[0] + (want.c_z * z[0] + want.c_x * x[0]) / plane.k,
                    p[1] + (want.c_z * z[1] + want.c_x * x[1]) / plane.k,
                    plane.h,
                ];
                for k in 0..2 {
                    assert!(
                        (got.centre[k] - want_c[k]).abs() < 1e-2,
                        "{got:?} vs {want_c:?}"
                    );
                }
            }
        }
    }

    /// The slab holds the view ray's medium beyond p: on the light's far face with the view
    /// going up into the slab, the slab grows below p by μ_V × the medium the view ray is
    /// known to have, p keeping its depth; a view whose ray holds all of the slab's path
    /// keeps the slab; a ray holding less than the slab's path moves p down to the far face.
    #[test]
    fn the_slab_holds_the_view_rays_medium() {
        let tables = crate::embedded::mie_10um();
        let sun = unit([0.0, 0.6, 0.8]);
        let plane = Plane { h: 200.0, k: 0.05 };
        let s = Chord(&plane, sun).filtered([0.0, 0.0, 0.0], 1.0).unwrap();
        let view = unit([0.3, -0.2, 0.5]);
        let mut vp = Viewpoint::new([0.0, 0.0, 0.0], view);
        let free = local_slab(&tables, &s, &vp, sun);
        assert!((free.at.depth - 10.0).abs() < 1e-4 && !free.clamps.view);
        vp.behind_min = 5.0;
        let held = local_slab(&tables, &s, &vp, sun);
        let want = 10.0 + view[2] * 5.0;
        assert!((held.at.depth - 10.0).abs() < 1e-4, "{held:?}");
        assert!((held.at.thickness - want).abs() < 1e-4, "{held:?}");
        assert!(!held.clamps.any(), "{held:?}");
        // From above, the ray holds at least 9 mfp: the lit face keeps d = 0.
        let mut top = Viewpoint::new([0.0, 0.0, 200.0], view);
        top.behind_min = 9.0;
        let at = local_slab(
            &tables,
            &Chord(&plane, sun).filtered(top.position, 1.0).unwrap(),
            &top,
            sun,
        );
        assert!(at.at.depth.abs() < 1e-4 && !at.clamps.view, "{at:?}");
        // Halfway down, the ray holds at most 2 mfp beyond p: p moves down to 2 μ_V above the
        // far face.
        let mut mid = Viewpoint::new([0.0, 0.0, 100.0], view);
        mid.behind_max = 2.0;
        let s = Chord(&plane, sun).filtered(mid.position, 1.0).unwrap();
        let thin = local_slab(&tables, &s, &mid, sun);
        assert!(
            (thin.at.depth - (10.0 - view[2] * 2.0)).abs() < 1e-4,
            "{thin:?}"
        );
        assert!(thin.clamps.view, "{thin:?}");
    }

    /// Seen going up, p lies no deeper than its own depth to the sun: the slab is cut above
    /// it, the medium below p kept, whether the view ray held p at the far face or not; a
    /// depth to the sun beyond p's, or a view going down, changes nothing.
    #[test]
    fn p_lies_no_deeper_than_its_depth_to_the_sun() {
        let tables = crate::embedded::mie_10um();
        let sun = unit([0.0, 0.6, 0.8]);
        let plane = Plane { h: 200.0, k: 0.05 };
        // p halfway down the 10-mfp slab, its ray holding at most 2 mfp beyond it.
        let s = Chord(&plane, sun).filtered([0.0, 0.0, 100.0], 1.0).unwrap();
        let view = unit([0.3, -0.2, 0.5]);
        let mut vp = Viewpoint::new([0.0, 0.0, 100.0], view);
        vp.behind_max = 2.0;
        let held = local_slab(&tables, &s, &vp, sun);
        let below = view[2] * 2.0;
        assert!((held.at.depth - (10.0 - below)).abs() < 1e-4, "{held:?}");
        assert!(held.clamps.view && !held.clamps.sun, "{held:?}");
        vp.sun_depth = 1.5;
        let cut = local_slab(&tables, &s, &vp, sun);
        let d_sun = 0.8 * 1.5;
        assert!(cut.clamps.view && cut.clamps.sun, "{cut:?}");
        assert!((cut.at.depth - d_sun).abs() < 1e-5, "{cut:?}");
        assert!((cut.at.thickness - (d_sun + below)).abs() < 1e-4, "{cut:?}");
        // Deeper to the sun than p lies, within the slab: nothing to do.
        vp.sun_depth = 12.0;
        assert_eq!(local_slab(&tables, &s, &vp, sun), held);
        // Deeper to the sun than the slab is thick (d_☉ = 16 mfp): the slab grows at its lit
        // face by 6 mfp, p with it.
        vp.sun_depth = 20.0;
        let grown = local_slab(&tables, &s, &vp, sun);
        assert!(grown.clamps.sun, "{grown:?}");
        assert!((grown.at.thickness - 16.0).abs() < 1e-4, "{grown:?}");
        assert!(
            (grown.at.depth - (held.at.depth + 6.0)).abs() < 1e-4,
            "{grown:?}"
        );
        vp.sun_depth = 12.0;
        let down = Viewpoint {
            view: [view[0], view[1], -view[2]],
            sun_depth: 1.5,
            ..vp
        };
        assert!(!local_slab(&tables, &s, &down, sun).clamps.sun);
        // Nothing known beyond p: the slab below p (5 mfp) is kept.
        let open = Viewpoint {
            sun_depth: 1.5,
            ..Viewpoint::new(vp.position, view)
        };
        let cut = local_slab(&tables, &s, &open, sun);
        assert!(cut.clamps.sun && !cut.clamps.view, "{cut:?}");
        assert!((cut.at.depth - d_sun).abs() < 1e-5, "{cut:?}");
        assert!((cut.at.thickness - (d_sun + 5.0)).abs() < 1e-4, "{cut:?}");
    }

    /// The plane as a light-space map sees it: the chord along the light is t/μ_L.
    struct Chord<'a>(&'a Plane, Vec3<f32>);

    impl LitSurface for Chord<'_> {
        fn filtered(&self, at: Vec3<f32>, sigma: f32) -> Option<FilteredSurface> {
            let mut s = self.0.filtered(at, sigma)?;
            // The entry on the light line through `at`.
            let back = (self.0.h - at[2]) / self.1[2];
            s.entry = add(at, self.1, back);
            s.length /= self.1[2];
            s.optical_length /= self.1[2];
            Some(s)
        }
        fn initial_scale(&self) -> f32 {
            self.0.initial_scale()
        }
    }

    /// A ball of radius r at the origin, filtered by blending its normal toward the sun with
    /// the scale (a stand-in for map filtering, symmetric like it).
    struct Ball {
        r: f32,
        k: f32,
        sun: Vec3<f32>,
    }

    impl Ball {
        /// 400 m of κ = 0.05/m (20 mfp across its radius) under a sun toward (0, 0.5, 0.8).
        fn lit() -> (Vec3<f32>, Self) {
            let sun = unit([0.0, 0.5, 0.8]);
            let ball = Ball {
                r: 400.0,
                k: 0.05,
                sun,
            };
            (sun, ball)
        }
    }

    impl LitSurface for Ball {
        fn filtered(&self, at: Vec3<f32>, sigma: f32) -> Option<FilteredSurface> {
            // Distance of the light line from the centre.
            let along = dot(at, self.sun);
            let perp = add(at, self.sun, -along);
            let q = dot(perp, perp);
            if q >= self.r * self.r {
                return None;
            }
            let half = (self.r * self.r - q).sqrt();
            let entry = add(perp, self.sun, half);
            let w = (sigma / self.r).min(1.0);
            let normal = unit(add(entry.map(|x| x / self.r * (1.0 - w)), self.sun, w));
            Some(FilteredSurface {
                entry,
                normal,
                length: 2.0 * half,
                optical_length: 2.0 * half * self.k,
            })
        }
        fn initial_scale(&self) -> f32 {
            self.r
        }
        fn sun_depth(&self, at: Vec3<f32>) -> Option<f32> {
            let along = dot(at, self.sun);
            let perp = add(at, self.sun, -along);
            let q = dot(perp, perp);
            let half = (self.r * self.r - q).max(0.0).sqrt();
            Some(self.k * (half - along).clamp(0.0, 2.0 * half))
        }
    }

    /// With each group's sun depth spread across the light, the search of all groups at once is
    /// still each group's own, bit for bit (the first read shared only where the groups' slabs
    /// are the same), and the spread moves the groups whose disk reaches shallower or deeper
    /// matter than p's own light line.
    #[test]
    fn spread_sun_depths_keep_the_groups_searches_their_own() {
        let tables = crate::embedded::mie_10um();
        let (sun, ball) = Ball::lit();
        let spread = SearchOptions::for_tables(&tables);
        let g = spread.sun_spread.expect("a mean cosine");
        assert!((g - 0.86).abs() < 0.02, "{g}");
        let mut moved = 0;
        for (p, view) in [
            ([150.0, 200.0, 250.0], unit([0.4, 0.6, 0.5])),
            ([-100.0, -300.0, 100.0], unit([-0.2, -0.9, 0.1])),
            ([250.0, -100.0, -200.0], unit([0.5, -0.3, -0.8])),
            ([0.0, -150.0, -340.0], unit([0.1, -0.2, -0.97])),
        ] {
            let p = unit(p).map(|x| x * 380.0);
            let v = Viewpoint {
                sun_depth: ball.sun_depth(p).unwrap(),
                ..Viewpoint::new(p, view)
            };
            let mut all = [None; MAX_GROUPS];
            find_collectors(&tables, &ball, &v, sun, &spread, &mut all);
            let mut own = [None; MAX_GROUPS];
            find_collectors(&tables, &ball, &v, sun, &SearchOptions::default(), &mut own);
            for g in 0..tables.groups() {
                let one = find_collector(&tables, g, &ball, &v, sun, &spread);
                assert_eq!(all[g], one, "group {g} at {p:?}");
                moved += usize::from(all[g] != own[g]);
            }
        }
        assert!(moved > 0, "the spread changed nothing");
        // No room for any group: nothing to do, and no panic.
        let p = [0.0, 0.0, 100.0];
        find_collectors(
            &tables,
            &ball,
            &Viewpoint::new(p, sun),
            sun,
            &spread,
            &mut [],
        );
    }

    /// Mirroring p and the view across the plane that holds the sun and the ball's centre
    /// mirrors the collector and keeps T and σ.
    #[test]
    fn a_ball_gives_answers_symmetric_about_the_suns_plane() {
        let tables = crate::embedded::mie_10um();
        let (sun, ball) = Ball::lit();
        // The sun's plane here is x = 0: mirror x.
        let m = |v: Vec3<f32>| [-v[0], v[1], v[2]];
        let mut total_reads = 0;
        let mut n = 0;
        for (p, view) in [
            ([150.0, 200.0, 250.0], unit([0.4, 0.6, 0.5])),
            ([-100.0, -300.0, 100.0], unit([-0.2, -0.9, 0.1])),
            ([250.0, -100.0, -200.0], unit([0.5, -0.3, -0.8])),
        ] {
            let p = unit(p).map(|x| x * 380.0);
            for g in 0..tables.groups() {
                let o = SearchOptions::default();
                let (va, vb) = (Viewpoint::new(p, view), Viewpoint::new(m(p), m(view)));
                let a = find_collector(&tables, g, &ball, &va, sun, &o).expect("lit");
                let b = find_collector(&tables, g, &ball, &vb, sun, &o).expect("lit");
                let close = |x: f32, y: f32| (x - y).abs() <= 1e-3 * (1.0 + x.abs());
                assert!(close(a.transport.t, b.transport.t), "T {a:?} {b:?}");
                assert!(close(a.sigma, b.sigma), "σ");
                let mc = m(a.centre);
                for k in 0..3 {
                    assert!((mc[k] - b.centre[k]).abs() < 0.05, "c {a:?} {b:?}");
                }
                assert_eq!(a.reads, b.reads);
                total_reads += a.reads;
                n += 1;
            }
        }
        std::println!(
            "ball: {:.2} reads per search",
            total_reads as f32 / n as f32
        );
    }
}
