//! Shared helpers of the experiments: CSV output, reference-data loading, plotting,
//! summary statistics, (re-exported from `sph-core`) the seeded generator, and the angle-of-repose
//! experiments' shared runs, measures and outputs ([`repose`]).

mod data;
mod plot;
pub mod repose;
pub mod solar_system;
pub mod stats;

pub use data::{load_reference_csv, write_csv_columns, write_csv_rows, ReferenceTable};
pub use plot::{ensure_fonts, plot_xy, Legend, Marker, PlotSpec, Series, SeriesStyle};
pub use sph_core::random::SplitMix64;
mod particle_image;
pub use particle_image::side_view_png;
