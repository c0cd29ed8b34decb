//! `aperture bench`'s log-log plot of relative MSE against render time.

use crate::bench_results::Series;
use crate::plot::{draw_legend, load_font, tick_label, write_png, PALETTE};
use anyhow::bail;
use std::path::Path;

/// Writes the log-log plot of relative MSE against render time, one curve per configuration,
/// as SVG and PNG (text laid out with a system font; see [`load_font`]).
pub(crate) fn plot_error_vs_time(
    series: &Series,
    title: &str,
    svg: &Path,
    png: &Path,
) -> anyhow::Result<()> {
    use plotters::prelude::*;
    const SIZE: (u32, u32) = (960, 640);
    // Both backends measure text with the registered font.
    if !load_font() {
        bail!(
            "no TrueType font found for the plot's labels (set APERTURE_FONT to a .ttf file); \
             {} and {} not written",
            svg.display(),
            png.display()
        );
    }
    {
        let root = SVGBackend::new(svg, SIZE).into_drawing_area();
        draw_plot(&root, series, title).map_err(|e| anyhow::anyhow!("plotting: {e}"))?;
        root.present()
            .map_err(|e| anyhow::anyhow!("writing {}: {e}", svg.display()))?;
    }
    write_png(png, SIZE, |root| {
        draw_plot(root, series, title).map_err(|e| anyhow::anyhow!("plotting: {e}"))
    })
}

fn draw_plot<DB: plotters::prelude::DrawingBackend>(
    root: &plotters::prelude::DrawingArea<DB, plotters::coord::Shift>,
    series: &Series,
    title: &str,
) -> Result<(), plotters::drawing::DrawingAreaErrorKind<DB::ErrorType>> {
    use plotters::prelude::*;
    let pts = series.iter().flat_map(|(_, p)| p.iter()).copied();
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for (x, y) in pts.filter(|&(x, y)| x > 0.0 && y > 0.0) {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if x0 > x1 {
        (x0, x1, y0, y1) = (1e-3, 1.0, 1e-4, 1.0);
    }
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(root)
        .caption(
            format!("Error against render time: {title}"),
            ("sans-serif", 24),
        )
        .margin(20)
        .x_label_area_size(55)
        .y_label_area_size(85)
        .build_cartesian_2d(
            (x0 / 1.3..x1 * 1.3).log_scale(),
            (y0 / 1.5..y1 * 1.5).log_scale(),
        )?;
    chart
        .configure_mesh()
        .x_desc("render time (s, wall clock, log scale)")
        .y_desc("relative MSE vs reference (log scale)")
        .axis_desc_style(("sans-serif", 18))
        .label_style(("sans-serif", 15))
        .x_label_formatter(&|v| tick_label(*v))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()?;
    let palette = PALETTE;
    let mut extras = 0;
    for (name, p) in series.iter() {
        // A configuration keeps its colour whichever others are plotted; extra series take
        // the others in turn.
        let slot = match name.as_str() {
            "sobol" => 0,
            "random" => 1,
            "adaptive" => 2,
            _ => {
                extras += 1;
                2 + extras
            }
        };
        let color = palette[slot % palette.len()];
        let p: Vec<(f64, f64)> = p
            .iter()
            .copied()
            .filter(|&(x, y)| x > 0.0 && y > 0.0)
            .collect();
        chart
            .draw_series(LineSeries::new(p.clone(), color.stroke_width(3)))?
            .label(name.as_str())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 24, y)], color.stroke_width(3))
            });
        chart.draw_series(p.iter().map(|&q| Circle::new(q, 5, color.filled())))?;
    }
    draw_legend(&mut chart, 18)
}
