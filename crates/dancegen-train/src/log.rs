//! The training log: `log.csv` (`step,loss,lr,grad_norm,steps_per_s` + one column per loss part)
//! and the loss-curve PNG drawn from it. `loss` and `steps_per_s` are over the steps since the
//! previous row; `lr`, `grad_norm` and the parts are those of the row's own step.

use std::path::Path;

use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};

use crate::TrainError;

/// DejaVu Sans (Bitstream Vera licence, see NOTICE), as in `dancegen-cli/src/plot.rs`: plotters
/// needs a font and the user's machine may have none.
const FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");
const WIDTH: u32 = 1200;
const HEIGHT: u32 = 600;

/// One logged step.
#[derive(Clone, Debug, PartialEq)]
pub struct LogRow {
    pub step: u64,
    pub loss: f64,
    pub lr: f64,
    pub grad_norm: f64,
    pub steps_per_s: f64,
    pub parts: Vec<(String, f64)>,
}

/// Rows of `log.csv`, in order.
#[derive(Clone, Debug, Default)]
pub struct TrainLog {
    pub rows: Vec<LogRow>,
}

impl TrainLog {
    /// Reads `path`, keeping rows up to `max_step` (a resumed run redoes the later steps).
    pub fn load(path: &Path, max_step: u64) -> Result<Self, TrainError> {
        let text = std::fs::read_to_string(path).map_err(|e| TrainError::io(path, e))?;
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
        let mut rows = Vec::new();
        for (n, line) in lines.enumerate() {
            let bad = || TrainError::io(path, format!("line {}: not a log row: {line}", n + 2));
            let v: Vec<f64> = line
                .split(',')
                .map(|s| s.parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|_| bad())?;
            if v.len() != header.len() || v.len() < 5 {
                return Err(bad());
            }
            let row = LogRow {
                step: v[0] as u64,
                loss: v[1],
                lr: v[2],
                grad_norm: v[3],
                steps_per_s: v[4],
                parts: header[5..]
                    .iter()
                    .zip(&v[5..])
                    .map(|(h, x)| (h.to_string(), *x))
                    .collect(),
            };
            if row.step <= max_step {
                rows.push(row);
            }
        }
        Ok(Self { rows })
    }

    /// Writes the CSV atomically.
    pub fn save(&self, path: &Path) -> Result<(), TrainError> {
        let mut s = String::from("step,loss,lr,grad_norm,steps_per_s");
        if let Some(r) = self.rows.first() {
            for (name, _) in &r.parts {
                s.push(',');
                s.push_str(name);
            }
        }
        s.push('\n');
        for r in &self.rows {
            s.push_str(&format!(
                "{},{},{},{},{}",
                r.step, r.loss, r.lr, r.grad_norm, r.steps_per_s
            ));
            for (_, v) in &r.parts {
                s.push_str(&format!(",{v}"));
            }
            s.push('\n');
        }
        dancegen_io::write_atomic(path, |w| w.write_all(s.as_bytes()))
            .map_err(|e| TrainError::io(path, e))
    }

    /// Draws loss against step to a PNG, atomically.
    pub fn plot(&self, path: &Path, title: &str) -> Result<(), TrainError> {
        let _ = register_font("sans-serif", FontStyle::Normal, FONT);
        let mut rgb = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
        draw(&mut rgb, &self.rows, title).map_err(|e| TrainError::io(path, e))?;
        dancegen_io::write_atomic(path, |w| {
            let mut enc = png::Encoder::new(w, WIDTH, HEIGHT);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let mut writer = enc.write_header().map_err(std::io::Error::other)?;
            writer
                .write_image_data(&rgb)
                .map_err(std::io::Error::other)?;
            writer.finish().map_err(std::io::Error::other)
        })
        .map_err(|e| TrainError::io(path, e))
    }
}

fn draw(rgb: &mut [u8], rows: &[LogRow], title: &str) -> Result<(), Box<dyn std::error::Error>> {
    let root = BitMapBackend::with_buffer(rgb, (WIDTH, HEIGHT)).into_drawing_area();
    root.fill(&WHITE)?;
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.loss.is_finite())
        .map(|r| (r.step as f64, r.loss))
        .collect();
    let x_max = pts.last().map_or(1.0, |p| p.0).max(1.0);
    let (lo, hi) = pts
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), p| (a.min(p.1), b.max(p.1)));
    let (lo, hi) = if pts.is_empty() {
        (0.0, 1.0)
    } else {
        let pad = ((hi - lo) * 0.05).max(hi.abs() * 1e-3).max(1e-12);
        (lo - pad, hi + pad)
    };
    let mut chart = ChartBuilder::on(&root)
        .margin(15)
        .caption(title, ("sans-serif", 22))
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(0f64..x_max, lo..hi)?;
    chart
        .configure_mesh()
        .x_desc("step")
        .y_desc("loss")
        .draw()?;
    chart.draw_series(LineSeries::new(pts, BLUE.stroke_width(2)))?;
    root.present()?;
    Ok(())
}
