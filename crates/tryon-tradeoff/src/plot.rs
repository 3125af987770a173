//! SVG scatter plots with the Pareto front (lower is better on both axes) marked.

use plotters::prelude::*;
use std::path::Path;

/// One named set of points (x, y), with a short label per point.
#[derive(Clone, Debug, Default)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64, String)>,
}

/// Points no other point beats on both coordinates (ties kept), sorted by x.
pub fn pareto(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut front: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|&(x, y)| {
            !points
                .iter()
                .any(|&(a, b)| a <= x && b <= y && (a < x || b < y))
        })
        .collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    front.dedup();
    front
}

/// How an axis is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scale {
    Linear,
    /// log10 of the value (values <= 0 are clamped to `floor`).
    Log {
        floor: f64,
    },
}

impl Scale {
    fn map(self, v: f64) -> f64 {
        match self {
            Scale::Linear => v,
            Scale::Log { floor } => v.max(floor).log10(),
        }
    }
    fn label(self, s: &str) -> String {
        match self {
            Scale::Linear => s.to_string(),
            Scale::Log { .. } => format!("log10 {s}"),
        }
    }
}

/// A scatter plot of `series` written to `path`; with `front`, the Pareto front over all points
/// is drawn as a line.
#[allow(clippy::too_many_arguments)]
pub fn scatter(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    xs: Scale,
    ys: Scale,
    series: &[Series],
    front: bool,
) -> Result<(), String> {
    let err = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
    let all: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| (xs.map(p.0), ys.map(p.1))))
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect();
    if all.is_empty() {
        return Err(format!("{}: no points to plot", path.display()));
    }
    let pad = |lo: f64, hi: f64| {
        let span = (hi - lo).abs().max(1e-9);
        (lo - 0.08 * span, hi + 0.08 * span)
    };
    let (x0, x1) = pad(
        all.iter().map(|p| p.0).fold(f64::INFINITY, f64::min),
        all.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max),
    );
    let (y0, y1) = pad(
        all.iter().map(|p| p.1).fold(f64::INFINITY, f64::min),
        all.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max),
    );
    let root = SVGBackend::new(path, (820, 520)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc(xs.label(x_label))
        .y_desc(ys.label(y_label))
        .draw()
        .map_err(|e| err(&e))?;
    for (k, s) in series.iter().enumerate() {
        let color = Palette99::pick(k).to_rgba();
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .map(|p| (xs.map(p.0), ys.map(p.1)))
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .collect();
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 5, color.filled())))
            .map_err(|e| err(&e))?
            .label(s.name.clone())
            .legend(move |(x, y)| Circle::new((x, y), 5, color.filled()));
        chart
            .draw_series(s.points.iter().filter_map(|p| {
                let q = (xs.map(p.0), ys.map(p.1));
                (q.0.is_finite() && q.1.is_finite())
                    .then(|| Text::new(p.2.clone(), (q.0, q.1), ("sans-serif", 11).into_font()))
            }))
            .map_err(|e| err(&e))?;
    }
    if front {
        let f = pareto(&all);
        chart
            .draw_series(LineSeries::new(f, BLACK.stroke_width(2)))
            .map_err(|e| err(&e))?
            .label("Pareto front")
            .legend(|(x, y)| PathElement::new(vec![(x - 10, y), (x + 10, y)], BLACK));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pareto_keeps_only_undominated_points() {
        let pts = [(1.0, 5.0), (2.0, 3.0), (3.0, 4.0), (4.0, 1.0), (2.0, 3.0)];
        assert_eq!(pareto(&pts), vec![(1.0, 5.0), (2.0, 3.0), (4.0, 1.0)]);
    }
}
