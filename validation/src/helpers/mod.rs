//! Shared helpers of the experiments: CSV output, reference-data loading, plotting,
//! summary statistics and a small deterministic random-number generator.

mod data;
mod plot;
mod rng;
pub mod solar_system;
pub mod stats;

pub use data::{load_reference_csv, write_csv_columns, write_csv_rows, ReferenceTable};
pub use plot::{ensure_fonts, plot_xy, Legend, Marker, PlotSpec, Series, SeriesStyle};
pub use rng::SplitMix64;
mod particle_image;
pub use particle_image::side_view_png;
