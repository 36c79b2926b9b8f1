//! `docs/scaling.png`: the scaling curves, drawn with plotters into an RGB
//! buffer and written with the `image` crate. Text needs a TrueType font,
//! registered at run time by `common::plot::register_font` (DejaVu Sans from
//! Debian's fonts-dejavu-core, or the file named by `PENUMBRA_BENCH_FONT`).

use std::path::Path;

use anyhow::Context as _;
use plotters::coord::Shift;
use plotters::prelude::*;

use common::plot::{err, register_font};

use crate::schema::Results;

type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;
/// (legend, colour, points).
type Series<'a> = (&'a str, RGBColor, Vec<(f64, f64)>);

fn upper(v: impl Iterator<Item = f64>) -> f64 {
    v.fold(0.0, f64::max) * 1.15
}

/// A panel with a log x axis (triangles) and two series on a linear y axis.
fn log_panel(
    area: &Area,
    title: &str,
    y_label: &str,
    series: &[Series],
    y_decimals: usize,
) -> anyhow::Result<()> {
    let xs = series.iter().flat_map(|s| s.2.iter().map(|p| p.0));
    let (x0, x1) = (
        xs.clone().fold(f64::INFINITY, f64::min) * 0.7,
        xs.fold(0.0, f64::max) * 1.4,
    );
    let y1 = upper(series.iter().flat_map(|s| s.2.iter().map(|p| p.1)));
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d((x0..x1).log_scale(), 0.0..y1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("triangles (log scale)")
        .y_desc(y_label)
        .x_label_formatter(&|x| format_count(*x))
        .y_label_formatter(&|y| format!("{y:.y_decimals$}"))
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(err)?;
    for (name, colour, points) in series {
        let c = *colour;
        chart
            .draw_series(LineSeries::new(points.clone(), c.stroke_width(2)))
            .map_err(err)?
            .label(*name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
        chart
            .draw_series(points.iter().map(|p| Circle::new(*p, 4, c.filled())))
            .map_err(err)?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()
        .map_err(err)?;
    Ok(())
}

/// A panel with linear axes and one series.
fn linear_panel(
    area: &Area,
    title: &str,
    x_label: &str,
    y_label: &str,
    points: &[(f64, f64)],
    colour: RGBColor,
) -> anyhow::Result<()> {
    let x1 = upper(points.iter().map(|p| p.0));
    let y1 = upper(points.iter().map(|p| p.1));
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..x1, 0.0..y1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .x_label_formatter(&|x| format!("{x:.1}"))
        .y_label_formatter(&|y| format!("{y:.0}"))
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(err)?;
    chart
        .draw_series(LineSeries::new(points.to_vec(), colour.stroke_width(2)))
        .map_err(err)?;
    chart
        .draw_series(points.iter().map(|p| Circle::new(*p, 4, colour.filled())))
        .map_err(err)?;
    Ok(())
}

fn format_count(x: f64) -> String {
    if x >= 1e6 {
        format!("{}M", x / 1e6)
    } else if x >= 1e3 {
        format!("{}k", x / 1e3)
    } else {
        format!("{x}")
    }
}

/// Draws the four scaling panels into `path`.
pub fn scaling(r: &Results, path: &Path) -> anyhow::Result<()> {
    register_font()?;
    let (w, h) = (1400u32, 1000u32);
    let mut buf = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let (title, body) = root.split_vertically(40);
        title
            .titled(
                &format!(
                    "penumbra on {} — {} — {}",
                    r.throughput.device.name, r.throughput.device.driver_info, r.date
                ),
                ("sans-serif", 18),
            )
            .map_err(err)?;
        let panels = body.split_evenly((2, 2));
        let tri = &r.scaling.triangles;
        let blue = RGBColor(31, 119, 180);
        let orange = RGBColor(255, 127, 14);
        let green = RGBColor(44, 160, 44);
        let red = RGBColor(214, 39, 40);
        log_panel(
            &panels[0],
            "Time vs triangles (1024×1024, BVH)",
            "milliseconds",
            &[
                (
                    "render, ms/frame (median)",
                    blue,
                    tri.iter()
                        .map(|t| (t.triangles as f64, t.render_ms.median))
                        .collect(),
                ),
                (
                    "BVH build, ms",
                    orange,
                    tri.iter()
                        .map(|t| (t.triangles as f64, t.bvh_build_ms))
                        .collect(),
                ),
            ],
            0,
        )?;
        log_panel(
            &panels[1],
            "BVH memory vs triangles",
            "MiB (nodes + primitive references)",
            &[(
                "BVH memory, MiB",
                green,
                tri.iter()
                    .map(|t| (t.triangles as f64, t.bvh_bytes as f64 / 1048576.0))
                    .collect(),
            )],
            1,
        )?;
        let px: Vec<(f64, f64)> = r
            .scaling
            .pixels
            .iter()
            .map(|p| (p.width as f64 * p.height as f64 / 1e6, p.render_ms.median))
            .collect();
        linear_panel(
            &panels[2],
            "Time vs pixels (bunny scene)",
            "megapixels",
            "ms/frame (median)",
            &px,
            blue,
        )?;
        let lights: Vec<(f64, f64)> = r
            .scaling
            .lights
            .iter()
            .map(|l| (l.lights as f64, l.render_ms.median))
            .collect();
        linear_panel(
            &panels[3],
            "Time vs directional lights (bunny, 1024×1024)",
            "lights",
            "ms/frame (median)",
            &lights,
            red,
        )?;
        root.present().map_err(err)?;
    }
    image::save_buffer(path, &buf, w, h, image::ExtendedColorType::Rgb8)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}
