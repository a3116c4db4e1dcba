//! Light transport in the canonical slab (thickness t in mean free paths, sun at μ_L = cos φ_L,
//! viewpoint at depth d from the lit face, view direction (μ_V, ψ_V) of the light travelling
//! toward the eye, μ_V > 0 going up, ψ_V from the sun's horizontal travel; [`SlabPoint`]).
//!
//! What a renderer uses: [`TransportTables`] (load a `.ntt`, evaluate T, c and σ per order
//! group: [`Transport`]), order 1 in closed form ([`single_scattering`]) and the collector
//! search on a cloud's lit surface ([`find_collector`], over the renderer's [`LitSurface`]).
//! The forms' insides — features, parameter grids, packing — are for the toolchain that fits
//! and writes the tables: the module `nephele_runtime::fitting`, behind the `fitting` feature.

/// A form's module: public (through `nephele_runtime::fitting`) only for the toolchain.
macro_rules! form_module {
    ($($name:ident),*) => {$(
        #[cfg(feature = "fitting")]
        pub mod $name;
        #[cfg(not(feature = "fitting"))]
        #[allow(dead_code)]
        mod $name;
    )*};
}

form_module!(collector, format, log_additive, single, tables);
pub mod batch;
mod domain;
mod finite;
mod geometry;
mod halo;
mod lanes;
pub mod leakage;
mod load;
#[cfg(feature = "std")]
mod owned;
mod search;
pub mod sun_depth;
mod surface;
mod thick;

#[cfg(feature = "std")]
pub use batch::column_names;
pub use batch::{evaluate_points, BatchError, Quantities, POINT_COLUMNS};
pub use domain::{Domain, Outside, OutsideTally, OutsideText};
pub use finite::{absorbed, finite_cloud, section_radius, FiniteCloud, Kept};
pub use format::MAX_GROUPS;
pub use geometry::{PointError, SlabPoint, COSINE_SLACK};
#[cfg(feature = "std")]
pub use owned::OwnedTables;
pub use search::{find_collector, find_collectors, local_slab};
pub use single::{scattering_cosine, single_scattering, PhaseValue};
pub use surface::{
    Clamps, Collector, FilteredSurface, Lateral, LitSurface, LocalSlab, SearchOptions, Unheld,
    Viewpoint,
};
pub use tables::{Transport, TransportTables};
