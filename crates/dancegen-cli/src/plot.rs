//! The `beats --plot` picture: waveform, onset envelope, onset peaks and beats on one time axis.

use std::path::Path;

use anyhow::{Result, bail};
use dancegen_music::Audio;
use dancegen_music::features::MusicFeatures;
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};

const WIDTH: u32 = 1600;
const HEIGHT: u32 = 800;
/// DejaVu Sans (Bitstream Vera licence, see NOTICE): plotters needs a font to draw labels and
/// we do not want to depend on the fonts installed on the user's machine.
const FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");

pub fn check_png_path(p: &Path) -> Result<()> {
    let ok = p
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if !ok {
        bail!(
            "{}: the plot is written as PNG; use a .png file name",
            p.display()
        );
    }
    Ok(())
}

pub fn beats_png(path: &Path, title: &str, audio: &Audio, f: &MusicFeatures) -> Result<()> {
    let _ = register_font("sans-serif", FontStyle::Normal, FONT);
    let mut rgb = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
    draw(&mut rgb, title, audio, f).map_err(|e| anyhow::anyhow!("drawing the plot: {e}"))?;
    let img: Vec<u8> = rgb;
    dancegen_io::write_atomic(path, |w| encode_png(w, &img))?;
    Ok(())
}

fn encode_png(w: &mut dyn std::io::Write, rgb: &[u8]) -> std::io::Result<()> {
    let mut enc = png::Encoder::new(w, WIDTH, HEIGHT);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut writer = enc.write_header().map_err(std::io::Error::other)?;
    writer
        .write_image_data(rgb)
        .map_err(std::io::Error::other)?;
    writer.finish().map_err(std::io::Error::other)
}

fn draw(
    rgb: &mut [u8],
    title: &str,
    audio: &Audio,
    f: &MusicFeatures,
) -> std::result::Result<(), Box<dyn std::error::Error>> {
    let root = BitMapBackend::with_buffer(rgb, (WIDTH, HEIGHT)).into_drawing_area();
    root.fill(&WHITE)?;
    let root = root.titled(
        &format!(
            "{title} — tempo {:.1} BPM, {} beats",
            f.tempo_bpm,
            f.beat_frames.len()
        ),
        ("sans-serif", 24),
    )?;
    let (top, bottom) = root.split_vertically(HEIGHT / 2 - 20);
    let duration = audio.duration_secs().max(1e-3);
    let beat_times = f.beat_times();

    // Waveform as a min/max envelope per pixel column.
    let y = &audio.samples;
    let cols = WIDTH as usize;
    let per = (y.len() / cols).max(1);
    let peak = y.iter().fold(0f32, |m, v| m.max(v.abs())).max(1e-6);
    let mut wave = ChartBuilder::on(&top)
        .margin(10)
        .caption("waveform and beats", ("sans-serif", 18))
        .x_label_area_size(30)
        .y_label_area_size(50)
        .build_cartesian_2d(0f64..duration, -peak..peak)?;
    wave.configure_mesh()
        .x_desc("time (s)")
        .disable_y_mesh()
        .draw()?;
    for c in 0..y.len().div_ceil(per) {
        let chunk = &y[c * per..((c + 1) * per).min(y.len())];
        let (lo, hi) = chunk
            .iter()
            .fold((f32::MAX, f32::MIN), |(a, b), &v| (a.min(v), b.max(v)));
        let t = (c * per) as f64 / audio.sample_rate as f64;
        wave.draw_series(std::iter::once(PathElement::new(
            vec![(t, lo), (t, hi)],
            RGBColor(90, 90, 90),
        )))?;
    }
    wave.draw_series(
        beat_times
            .iter()
            .map(|&t| PathElement::new(vec![(t, -peak), (t, peak)], RED.stroke_width(2))),
    )?
    .label("beats")
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED.stroke_width(2)));
    wave.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;

    // Onset envelope with onset peaks and beats.
    let env: Vec<f32> = (0..f.features.rows).map(|r| f.features.get(r, 0)).collect();
    let env_max = env.iter().cloned().fold(0f32, f32::max).max(1e-6) * 1.05;
    let fps = f.fps as f64;
    let mut oc = ChartBuilder::on(&bottom)
        .margin(10)
        .caption("onset strength, onset peaks and beats", ("sans-serif", 18))
        .x_label_area_size(30)
        .y_label_area_size(50)
        .build_cartesian_2d(0f64..duration, 0f32..env_max)?;
    oc.configure_mesh()
        .x_desc("time (s)")
        .y_desc("onset strength")
        .draw()?;
    oc.draw_series(
        beat_times
            .iter()
            .map(|&t| PathElement::new(vec![(t, 0.0), (t, env_max)], RED.mix(0.5).stroke_width(2))),
    )?;
    oc.draw_series(LineSeries::new(
        env.iter().enumerate().map(|(i, &v)| (i as f64 / fps, v)),
        BLUE.stroke_width(1),
    ))?
    .label("onset envelope")
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
    oc.draw_series(
        f.onset_frames
            .iter()
            .map(|&o| Circle::new((o as f64 / fps, env[o]), 3, GREEN.filled())),
    )?
    .label("onset peaks")
    .legend(|(x, y)| Circle::new((x + 10, y), 3, GREEN.filled()));
    oc.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}
