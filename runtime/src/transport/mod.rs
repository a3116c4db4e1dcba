//! Light transport in the canonical slab (thickness t in mean free paths, sun at μ_L = cos φ_L,
//! viewpoint at depth d from the lit face, view direction (μ_V, ψ_V) of the light travelling
//! toward the eye, μ_V > 0 going up, ψ_V from the sun's horizontal travel; [`SlabPoint`]).
//!
//! What a renderer uses: [`TransportTables`] (load a `.ntt`, evaluate T, c and σ per order
//! group: [`Transport`]) and order 1 in closed form ([`single_scattering`]). The forms' insides
//! — features, parameter grids, packing — are for the toolchain that fits and writes the
//! tables: the module [`fitting`], behind the `fitting` feature.

#[cfg_attr(not(feature = "fitting"), allow(dead_code))]
mod collector;
mod geometry;
#[cfg_attr(not(feature = "fitting"), allow(dead_code))]
mod log_additive;
#[cfg_attr(not(feature = "fitting"), allow(dead_code))]
mod single;
#[cfg_attr(not(feature = "fitting"), allow(dead_code))]
mod tables;

pub use geometry::SlabPoint;
pub use single::{scattering_cosine, single_scattering, PhaseValue};
pub use tables::{Transport, TransportTables};

/// The compressed forms' insides, for the toolchain that fits and writes the tables: the
/// features of T ([`fitting::LogAdditive`]) and of the collector ([`fitting::CollectorForm`]),
/// where a point sits among the parameter nodes ([`fitting::Cell`], [`fitting::Lerp`]), the
/// packed depth ranges and the runtime's size limits, which writers must respect.
#[cfg(feature = "fitting")]
pub mod fitting {
    pub use super::collector::{
        CollectorForm, Statistic, MAX_COLLECTOR_HARMONICS, MAX_COLLECTOR_LEGENDRE,
    };
    pub use super::log_additive::{
        legendre, ln_boundary, theta_hats, Cell, Lerp, LogAdditive, LN_F1_FLOOR, MAX_CROSS,
        MAX_HARMONICS, MAX_LEGENDRE, MAX_THETA_NODES,
    };
    pub use super::single::single_scattering_bin;
    pub use super::tables::{
        names, pack_u_range, stretched_u, unpack_u_range, MAX_GROUPS, MAX_NODES, MAX_Q, U_STEPS,
    };
}
