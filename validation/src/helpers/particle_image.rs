//! Side views of particle frames as PNG images (plotters), for figures like the PBF paper's
//! Fig. 5.

use std::path::Path;

use anyhow::{anyhow, bail, Result};
use plotters::prelude::*;

use super::ensure_fonts;

/// Draws particles projected on the x–y plane (m) as dots coloured by speed (blue slow,
/// red at or above `speed_max`, m/s), within `x_range` × `y_range`, scaled to `width` pixels.
pub fn side_view_png(
    path: &Path,
    title: &str,
    points: &[(f64, f64, f64)],
    x_range: (f64, f64),
    y_range: (f64, f64),
    speed_max: f64,
    width: u32,
) -> Result<()> {
    ensure_fonts();
    let (dx, dy) = (x_range.1 - x_range.0, y_range.1 - y_range.0);
    if !(dx > 0.0 && dy > 0.0 && width >= 100) {
        bail!("side view {}: empty range or width", path.display());
    }
    let height = ((width as f64 * dy / dx) as u32 + 90).clamp(150, 4000);
    let draw = || -> std::result::Result<(), Box<dyn std::error::Error>> {
        let root = BitMapBackend::new(path, (width, height)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(50)
            .build_cartesian_2d(x_range.0..x_range.1, y_range.0..y_range.1)?;
        chart
            .configure_mesh()
            .x_desc("x (m)")
            .y_desc("y (m)")
            .disable_mesh()
            .draw()?;
        let scale = if speed_max > 0.0 { speed_max } else { 1.0 };
        chart.draw_series(points.iter().map(|&(x, y, v)| {
            let f = (v / scale).clamp(0.0, 1.0);
            let c = RGBColor(
                (40.0 + 215.0 * f) as u8,
                (90.0 * (1.0 - f)) as u8,
                (220.0 * (1.0 - f)) as u8,
            );
            Circle::new((x, y), 1, c.filled())
        }))?;
        root.present()?;
        Ok(())
    };
    draw().map_err(|e| anyhow!("drawing {}: {e}", path.display()))
}
