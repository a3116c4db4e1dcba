//! Slab Monte Carlo and the canonical transport tables ⟨T, c, σ⟩ of Bouthors et al. 2008
//! (docs/slab.md).
//!
//! - [`grid`]: tally planes, view-direction bins, order groups.
//! - [`aureole`]: cones around the transmitted beam, the halo the view bins smear.
//! - [`walk`]: the photon walk of one slice (t, μ_L) and its per-batch random streams.
//! - [`lanes`]: the walk's photons side by side in SIMD lanes, their streams and free paths.
//! - [`tally`]: per-batch sums, batch-means statistics, the tables of a slice.
//! - [`run`]: a slice run to its stopping rule, deterministic for any thread count.
//! - [`single`]: the order-1 collector by quadrature, for validation (T₁ itself is the
//!   runtime's closed form).
//! - [`config`], [`tables`]: a whole run over (t, μ_L) from a config.
//! - [`output`]: tables.npz and tables.json, written and read.
//! - [`checkpoint`]: exact sums of finished and running slices, for resuming and for shards.

pub mod aureole;
pub mod checkpoint;
pub mod config;
pub mod grid;
pub mod lanes;
pub mod output;
pub mod run;
pub mod single;
pub mod tables;
pub mod tally;
pub mod walk;

pub use config::SlabConfig;
pub use grid::SlabGrid;
pub use output::SlabTables;
pub use run::{run_slice, run_slice_from, SliceReport, SliceRun, StopRule};
pub use walk::Slice;
