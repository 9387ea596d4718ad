//! The sweep's Pareto plot, drawn with `plotters` as SVG and as PNG: relMSE against GPU time
//! to the image, both log-scaled, a dot per configuration coloured by method, the Pareto
//! front as a line with its points ringed, a title, axis labels with units, tick values and
//! a legend, so that either picture reads on its own.
//!
//! Text needs a font: DejaVu Sans (`assets/fonts/`, Bitstream Vera licence, which allows
//! redistribution) is embedded in the binary and registered with plotters' `ab_glyph` text
//! renderer, so no system font is needed at run time.

use super::sweep::pareto_front;
use crate::tune::SweepRow;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::sync::OnceLock;

/// The plot's size in pixels (the SVG's in user units).
pub const PLOT_SIZE: (u32, u32) = (640, 420);

/// The embedded font of every text in the plots.
const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
const FAMILY: &str = "sans-serif";

/// A plot that could not be drawn (the font did not load, or plotters failed).
#[derive(Debug, thiserror::Error)]
#[error("the Pareto plot of {scene} could not be drawn: {reason}")]
pub struct PlotError {
    pub scene: String,
    pub reason: String,
}

/// Registers [`FONT`] as the plots' family once per process.
fn register_font() -> Result<(), String> {
    static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            plotters::style::register_font(FAMILY, FontStyle::Normal, FONT)
                .map_err(|_| "the embedded font DejaVuSans.ttf is not a valid font".to_owned())
        })
        .clone()
}

/// A method's colour: its spec's ([`crate::gi::MethodSpec::plot_colour`]); brown for a method
/// a CSV from another build names and this one lacks.
fn method_colour(method: &str) -> RGBColor {
    let hex = crate::gi::GiMethod::from_name(method).map_or("#8c564b", |m| m.spec().plot_colour);
    let channel = |i: usize| {
        hex.get(i..i + 2)
            .and_then(|h| u8::from_str_radix(h, 16).ok())
            .unwrap_or(0)
    };
    RGBColor(channel(1), channel(3), channel(5))
}

/// The decades [10^lo, 10^hi] covering the positive, finite values.
fn decades(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| *v > 0.0 && v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (1.0, 10.0);
    }
    let (l, h) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    (10f64.powi(l), 10f64.powi(h.max(l + 1)))
}

/// A tick value as people write it: 0.05, 2, 300; powers of ten outside [0.001, 10⁴).
fn tick(v: &f64) -> String {
    if *v >= 1e-3 && *v < 1e4 {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        format!("{v:.0e}")
    }
}

/// Draws the plot of `rows` (one scene's) onto `root`.
fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    scene: &str,
    rows: &[&SweepRow],
) -> Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(err)?;
    let (x0, x1) = decades(rows.iter().map(|r| r.image_ms));
    let (y0, y1) = decades(rows.iter().map(|r| r.rel_mse));
    // Values outside the decades (zero error, say) sit on the axis instead of vanishing.
    let at = |r: &SweepRow| (r.image_ms.clamp(x0, x1), r.rel_mse.clamp(y0, y1));
    let mut chart = ChartBuilder::on(root)
        .caption(
            format!("{scene}: error against GPU time (log–log)"),
            (FAMILY, 17),
        )
        .margin(12)
        .x_label_area_size(42)
        .y_label_area_size(58)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("GPU time to the image (ms)")
        .y_desc("relMSE (relative squared error, unitless)")
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .label_style((FAMILY, 12))
        .axis_desc_style((FAMILY, 13))
        .light_line_style(WHITE)
        .bold_line_style(RGBColor(0xdd, 0xdd, 0xdd))
        .draw()
        .map_err(err)?;

    let points: Vec<(f64, f64)> = rows.iter().map(|r| (r.image_ms, r.rel_mse)).collect();
    let front = pareto_front(&points);
    let front_line = front.iter().map(|&i| at(rows[i]));
    chart
        .draw_series(LineSeries::new(front_line, BLACK.stroke_width(2)))
        .map_err(err)?
        .label("Pareto front")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK.stroke_width(2)));
    let rings = front
        .iter()
        .map(|&i| Circle::new(at(rows[i]), 6, BLACK.stroke_width(2)));
    chart.draw_series(rings).map_err(err)?;

    let mut methods: Vec<&str> = rows.iter().map(|r| r.method.as_str()).collect();
    methods.sort_unstable();
    methods.dedup();
    for method in methods {
        let colour = method_colour(method);
        let dots = rows
            .iter()
            .filter(|r| r.method == method)
            .map(|r| Circle::new(at(r), 4, colour.filled()));
        chart
            .draw_series(dots)
            .map_err(err)?
            .label(method)
            .legend(move |(x, y)| Circle::new((x + 9, y), 4, colour.filled()));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FAMILY, 12))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(err)?;
    root.present().map_err(err)
}

/// The plot of one scene's rows as an SVG document.
pub fn pareto_svg(scene: &str, rows: &[&SweepRow]) -> Result<String, PlotError> {
    let fail = |reason: String| PlotError {
        scene: scene.to_owned(),
        reason,
    };
    register_font().map_err(fail)?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, PLOT_SIZE).into_drawing_area();
        draw(&root, scene, rows).map_err(fail)?;
    }
    Ok(svg)
}

/// The same plot as an RGB bitmap of [`PLOT_SIZE`], text rendered with the embedded font.
pub fn pareto_png(scene: &str, rows: &[&SweepRow]) -> Result<image::RgbImage, PlotError> {
    let fail = |reason: String| PlotError {
        scene: scene.to_owned(),
        reason,
    };
    register_font().map_err(fail)?;
    let (w, h) = PLOT_SIZE;
    let mut pixels = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut pixels, PLOT_SIZE).into_drawing_area();
        draw(&root, scene, rows).map_err(fail)?;
    }
    image::RgbImage::from_raw(w, h, pixels)
        .ok_or_else(|| fail("the bitmap has the wrong size".to_owned()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(method: &str, ms: f64, rel_mse: f64) -> SweepRow {
        SweepRow {
            scene: "cornell".into(),
            config: format!("{method} {ms}"),
            method: method.into(),
            size: 32,
            frames: 5,
            gi_median_ms: ms,
            gi_min_ms: ms,
            gi_max_ms: ms,
            frame_median_ms: ms,
            frame_min_ms: ms,
            frame_max_ms: ms,
            accumulate_frames: 1,
            image_ms: ms,
            transient_bytes: 0,
            rel_mse,
            flip: 0.1,
            psnr_db: 30.0,
            ssim: 0.9,
            device: "test".into(),
            gi_toml: "{}".into(),
            flicker: None,
            ghost: None,
            lag_frames: None,
        }
    }

    fn rows() -> Vec<SweepRow> {
        vec![
            row("none", 1.0, 0.5),
            row("hemisphere", 4.0, 0.05),
            row("hemisphere", 8.0, 0.5),
            row("pathtrace", 40.0, 0.01),
        ]
    }

    #[test]
    fn the_svg_carries_title_axes_ticks_and_legend() {
        let rows = rows();
        let refs: Vec<&SweepRow> = rows.iter().collect();
        let svg = pareto_svg("cornell <box>", &refs).expect("draws");
        assert!(svg.starts_with("<svg"), "{svg}");
        for text in [
            "cornell &lt;box&gt;: error against GPU time",
            "GPU time to the image (ms)",
            "relMSE (relative squared error, unitless)",
            "Pareto front",
            "hemisphere",
            "pathtrace",
            "none",
            // Tick values, each on its own line inside its <text> element.
            "\n0.1\n",
            "\n10\n",
        ] {
            assert!(svg.contains(text), "no `{text}` in the SVG:\n{svg}");
        }
        // Four dots, three ringed front points (none, hemisphere 4 ms, pathtrace), and one
        // legend dot per method.
        assert_eq!(svg.matches("<circle").count(), 4 + 3 + 3, "{svg}");
    }

    #[test]
    fn the_png_has_text_in_its_title_band_and_dots_where_the_rows_are() {
        let rows = rows();
        let refs: Vec<&SweepRow> = rows.iter().collect();
        let img = pareto_png("cornell", &refs).expect("draws");
        assert_eq!(img.dimensions(), PLOT_SIZE);
        // The title band (above the plot area) holds dark glyph pixels, not only background.
        let dark = |x0: u32, y0: u32, x1: u32, y1: u32| {
            let mut n = 0;
            for y in y0..y1 {
                for x in x0..x1 {
                    let p = img.get_pixel(x, y).0;
                    n += usize::from(p.iter().all(|&c| c < 100));
                }
            }
            n
        };
        assert!(dark(0, 0, 640, 30) > 100, "no title text");
        // Tick values under the x axis and the axis label left of the plot.
        assert!(dark(60, 370, 640, 420) > 100, "no x tick values or label");
        assert!(dark(0, 40, 40, 370) > 50, "no y axis label");
        // Each method's colour appears.
        for m in ["none", "hemisphere", "pathtrace"] {
            let c = method_colour(m);
            let found = img.pixels().any(|p| p.0 == [c.0, c.1, c.2]);
            assert!(found, "no {m} dot");
        }
    }
}
