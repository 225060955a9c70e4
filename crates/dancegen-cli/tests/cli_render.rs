//! The `render` command: PNG and GIF previews of an AIST++ motion decode and show the figure;
//! MP4 goes through ffmpeg when it is installed and fails with a clear message otherwise.

mod common;

use std::path::Path;
use std::process::Command;

use common::*;

const AIST: &str = "data/aistpp/motions/gBR_sBM_cAll_d04_mBR2_ch08.pkl";

/// Saturated pixels: the dancers (background, floor and grid are near-grey).
fn figure_pixels(rgb: &[u8]) -> usize {
    rgb.chunks(3)
        .filter(|p| {
            let mx = p.iter().copied().max().unwrap() as i32;
            let mn = p.iter().copied().min().unwrap() as i32;
            mx - mn > 60
        })
        .count()
}

#[test]
fn png_shows_the_dancer() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p.png");
    let src = shared().join(AIST);
    let o = dancegen(&[
        "render",
        src.to_str().unwrap(),
        "--width",
        "320",
        "--height",
        "240",
        "--frame",
        "100",
        "-o",
        out.to_str().unwrap(),
    ]);
    ok(&o);
    assert!(String::from_utf8_lossy(&o.stdout).contains("1 dancer(s)"));
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&out).unwrap()));
    let mut r = dec.read_info().unwrap();
    let mut buf = vec![0; r.output_buffer_size().unwrap()];
    let info = r.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (320, 240));
    assert_eq!(info.color_type, png::ColorType::Rgb);
    let n = figure_pixels(&buf[..info.buffer_size()]);
    assert!(n > 300, "{n} figure pixels");
    // Nothing but the output in the directory (the write is atomic).
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn gif_of_two_dancers_animates() {
    let dir = tempfile::tempdir().unwrap();
    // Two dancers: the AIST++ motion (capsules) and its joints shifted by 1.5 m along x as an
    // .npy joint array (spheres only).
    let src = shared().join(AIST);
    let npy = dir.path().join("j.npy");
    ok(&dancegen(&[
        "-q",
        "convert",
        src.to_str().unwrap(),
        "--fps",
        "30",
        "-o",
        npy.to_str().unwrap(),
    ]));
    let a = dancegen_io::read_npy(&npy).unwrap();
    let mut shifted: Vec<f32> = a.data.iter().map(|&v| v as f32).collect();
    for p in shifted.chunks_mut(3) {
        p[0] += 1.5;
    }
    dancegen_io::write_npy_f32(&npy, &a.shape, &shifted).unwrap();
    let out = dir.path().join("a.gif");
    // 575/60 s at 5 fps = 48 frames.
    ok(&dancegen(&[
        "-q",
        "render",
        src.to_str().unwrap(),
        npy.to_str().unwrap(),
        "--fps",
        "5",
        "--width",
        "320",
        "--height",
        "240",
        "-o",
        out.to_str().unwrap(),
    ]));
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::RGBA);
    let mut d = opts.read_info(std::fs::File::open(&out).unwrap()).unwrap();
    assert_eq!((d.width(), d.height()), (320, 240));
    let mut frames = 0;
    let mut first_figure = 0;
    while let Some(f) = d.read_next_frame().unwrap() {
        if frames == 0 {
            let rgb: Vec<u8> = f
                .buffer
                .chunks(4)
                .flat_map(|p| [p[0], p[1], p[2]])
                .collect();
            first_figure = figure_pixels(&rgb);
            let blue = rgb
                .chunks(3)
                .filter(|p| p[2] as i32 > p[0] as i32 + 60)
                .count();
            let orange = rgb
                .chunks(3)
                .filter(|p| p[0] as i32 > p[2] as i32 + 80)
                .count();
            assert!(blue > 100 && orange > 100, "blue {blue} orange {orange}");
        }
        assert_eq!(f.delay, 20);
        frames += 1;
    }
    assert_eq!(frames, 48);
    assert!(first_figure > 300, "{first_figure}");
}

fn ffmpeg_on_path() -> bool {
    Command::new("ffmpeg")
        .arg("-version")
        .output()
        .is_ok_and(|o| o.status.success())
}

#[test]
fn mp4_uses_ffmpeg_or_says_to_install_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("v.mp4");
    let src = shared().join(AIST);
    let args = [
        "-q",
        "render",
        src.to_str().unwrap(),
        "--fps",
        "5",
        "--width",
        "320",
        "--height",
        "240",
        "-o",
        out.to_str().unwrap(),
    ];
    if ffmpeg_on_path() {
        ok(&dancegen(&args));
        let bytes = std::fs::read(&out).unwrap();
        assert_eq!(&bytes[4..8], b"ftyp");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        // With --audio the song is muxed in: the file has a video and an audio stream.
        let song =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/demo_metal_madness_45s.ogg");
        let with_audio = dir.path().join("a.mp4");
        let mut a: Vec<&str> = args[..args.len() - 2].to_vec();
        a.extend([
            "--audio",
            song.to_str().unwrap(),
            "-o",
            with_audio.to_str().unwrap(),
        ]);
        ok(&dancegen(&a));
        let probe = Command::new("ffprobe")
            .args([
                "-v",
                "error",
                "-show_entries",
                "stream=codec_type",
                "-of",
                "csv=p=0",
            ])
            .arg(&with_audio)
            .output()
            .expect("ffprobe comes with ffmpeg");
        let streams = String::from_utf8_lossy(&probe.stdout);
        assert!(
            streams.contains("video") && streams.contains("audio"),
            "streams: {streams}"
        );
    }
    // Without ffmpeg (forced here, so this part always runs) the error says what to do.
    let o = Command::new(env!("CARGO_BIN_EXE_dancegen"))
        .args(args)
        .env("DANCEGEN_FFMPEG", dir.path().join("no-such-ffmpeg"))
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("install ffmpeg") && err.contains(".gif"),
        "{err}"
    );
}

#[test]
fn unknown_extension_is_rejected() {
    let src = shared().join(AIST);
    let o = dancegen(&["render", src.to_str().unwrap(), "-o", "x.avi"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains(".png, .gif or .mp4"));
}

/// The ffmpeg pipe with a stand-in ffmpeg: raw YUV 4:2:0 frames on stdin, the encoder options, the
/// audio as a second input with `-shortest`, and the temporary `.mp4` renamed into place.
#[cfg(unix)]
#[test]
fn mp4_pipes_raw_frames_to_ffmpeg() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("args.txt");
    let fake = dir.path().join("fake-ffmpeg");
    std::fs::write(
        &fake,
        format!(
            "#!/bin/sh\n[ \"$1\" = -version ] && exit 0\necho \"$@\" > '{}'\nn=$(wc -c)\necho $n >> '{}'\nfor a; do last=$a; done\nprintf 'xxxxftypisom' > \"$last\"\n",
            log.display(),
            log.display()
        ),
    )
    .unwrap();
    std::fs::set_permissions(&fake, std::fs::Permissions::from_mode(0o755)).unwrap();
    let out_dir = dir.path().join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let out = out_dir.join("v.mp4");
    let src = shared().join(AIST);
    let o = Command::new(env!("CARGO_BIN_EXE_dancegen"))
        .args([
            "-q",
            "render",
            src.to_str().unwrap(),
            "--audio",
            src.to_str().unwrap(),
            "--fps",
            "5",
            "--width",
            "64",
            "--height",
            "48",
            "--draft",
            "-o",
            out.to_str().unwrap(),
        ])
        .env("DANCEGEN_FFMPEG", &fake)
        .output()
        .unwrap();
    ok(&o);
    let args = std::fs::read_to_string(&log).unwrap();
    for want in [
        "-f rawvideo",
        "-pix_fmt yuv420p -s 64x48",
        "-framerate 5",
        "-c:v libx264",
        "-pix_fmt yuv420p",
        "-shortest",
    ] {
        assert!(args.contains(want), "{want} missing in {args}");
    }
    // 576 frames at 60 fps last 575/60 s: 48 frames at 5 fps, of 64x48 YUV 4:2:0 (1.5 bytes
    // a pixel).
    let bytes: usize = args.lines().last().unwrap().trim().parse().unwrap();
    assert_eq!(bytes, 48 * 64 * 48 * 3 / 2);
    assert_eq!(&std::fs::read(&out).unwrap()[4..8], b"ftyp");
    assert_eq!(std::fs::read_dir(&out_dir).unwrap().count(), 1);
}
