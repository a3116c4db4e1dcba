//! Statistical tests and quadratures shared by every stage (sampling routines are all checked
//! the same way).

pub mod gauss;

pub use nephele_stats::{adaptive_simpson, chi2, splitmix64};
