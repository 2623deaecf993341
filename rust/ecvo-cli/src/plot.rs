//! `trajectory.svg`: a top view of the estimate against the ground truth, and the
//! ATE error over time.

use std::path::Path;

use anyhow::{Result, anyhow};
use ecvo_io::Trajectory;
use ecvo_io::eval::AteResult;
use plotters::prelude::*;

/// The plane of the top view: two world axes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Plane {
    /// x to the right, y up.
    Xy,
    /// x to the right, z up (the floor plane of the TUM benchmark's first camera).
    Xz,
    /// y to the right, z up.
    Yz,
}

impl Plane {
    fn axes(self) -> (usize, usize, &'static str, &'static str) {
        match self {
            Plane::Xy => (0, 1, "x (m)", "y (m)"),
            Plane::Xz => (0, 2, "x (m)", "z (m)"),
            Plane::Yz => (1, 2, "y (m)", "z (m)"),
        }
    }
}

const WIDTH: u32 = 900;
const TOP_HEIGHT: u32 = 700;
const BOTTOM_HEIGHT: u32 = 300;

fn err<E: std::fmt::Debug>(e: E) -> anyhow::Error {
    anyhow!("drawing failed: {e:?}")
}

/// Range `[lo, hi]` of `values`, padded, never empty.
fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(0.01);
    (lo - pad, hi + pad)
}

/// Writes the plot. The estimate is drawn after the ATE alignment (so in the ground
/// truth's frame) when `ate` is given; the ground truth is drawn over the time span
/// of the estimate only.
pub fn write_trajectory_svg(
    path: &Path,
    est: &Trajectory,
    gt: Option<&Trajectory>,
    ate: Option<&AteResult>,
    plane: Plane,
    title: &str,
) -> Result<()> {
    let (a, b, xlabel, ylabel) = plane.axes();
    let shown_est = match ate {
        Some(ate) => ate.aligned(est),
        None => est.clone(),
    };
    let t0 = est.stamps.first().copied().unwrap_or(0.0);
    let t1 = est.stamps.last().copied().unwrap_or(0.0);
    let gt_pts: Vec<(f64, f64)> = match (gt, ate) {
        (Some(gt), Some(_)) => gt
            .iter()
            .filter(|(t, _)| *t >= t0 - 0.02 && *t <= t1 + 0.02)
            .map(|(_, p)| (p.translation.vector[a], p.translation.vector[b]))
            .collect(),
        _ => Vec::new(),
    };
    let est_pts: Vec<(f64, f64)> = shown_est
        .poses
        .iter()
        .map(|p| (p.translation.vector[a], p.translation.vector[b]))
        .collect();

    // Equal scales on both axes: widen the narrower range to the panel's aspect.
    let all = || est_pts.iter().chain(&gt_pts);
    let (mut x0, mut x1) = range(all().map(|p| p.0));
    let (mut y0, mut y1) = range(all().map(|p| p.1));
    let aspect = (WIDTH as f64 - 90.0) / (TOP_HEIGHT as f64 - 110.0);
    let (w, h) = (x1 - x0, y1 - y0);
    if w / h < aspect {
        let extra = (h * aspect - w) / 2.0;
        x0 -= extra;
        x1 += extra;
    } else {
        let extra = (w / aspect - h) / 2.0;
        y0 -= extra;
        y1 += extra;
    }

    let root = SVGBackend::new(path, (WIDTH, TOP_HEIGHT + BOTTOM_HEIGHT)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let (top, bottom) = root.split_vertically(TOP_HEIGHT);

    let caption = match ate {
        Some(a) => format!("{title}: ATE RMSE {:.4} m", a.rmse),
        None => format!("{title} (no ground truth)"),
    };
    let mut chart = ChartBuilder::on(&top)
        .caption(caption, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(36)
        .y_label_area_size(56)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(xlabel)
        .y_desc(ylabel)
        .draw()
        .map_err(err)?;
    if !gt_pts.is_empty() {
        chart
            .draw_series(LineSeries::new(
                gt_pts.iter().copied(),
                BLACK.stroke_width(2),
            ))
            .map_err(err)?
            .label("ground truth")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(2)));
    }
    let est_label = if ate.is_some() {
        "estimate (aligned)"
    } else {
        "estimate"
    };
    chart
        .draw_series(LineSeries::new(
            est_pts.iter().copied(),
            RED.stroke_width(2),
        ))
        .map_err(err)?
        .label(est_label)
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED.stroke_width(2)));
    if let Some(&p) = est_pts.first() {
        chart
            .draw_series(std::iter::once(Circle::new(p, 4, BLUE.filled())))
            .map_err(err)?
            .label("start")
            .legend(|(x, y)| Circle::new((x + 10, y), 4, BLUE.filled()));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(err)?;

    match ate {
        Some(ate) => {
            let errs: Vec<(f64, f64)> = ate
                .pairs
                .iter()
                .zip(&ate.errors)
                .map(|(&(_, j), &e)| (est.stamps[j] - t0, e))
                .collect();
            let tmax = errs.iter().map(|p| p.0).fold(0.0, f64::max).max(1e-3);
            let emax = ate.max.max(1e-4) * 1.1;
            let mut chart = ChartBuilder::on(&bottom)
                .caption("ATE error over time", ("sans-serif", 16))
                .margin(12)
                .x_label_area_size(36)
                .y_label_area_size(56)
                .build_cartesian_2d(0.0..tmax, 0.0..emax)
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc("time (s)")
                .y_desc("error (m)")
                .draw()
                .map_err(err)?;
            chart
                .draw_series(LineSeries::new(errs, RED.stroke_width(1)))
                .map_err(err)?;
        }
        None => {
            bottom
                .draw(&Text::new(
                    "no ground truth: no ATE error to plot",
                    (40, 40),
                    ("sans-serif", 16).into_font(),
                ))
                .map_err(err)?;
        }
    }
    root.present().map_err(err)?;
    Ok(())
}
