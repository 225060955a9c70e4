//! A one-hour song is decoded and resampled as a stream: peak heap stays near the size of the
//! output signal, never the size of the decoded multi-channel file.

use std::alloc::{GlobalAlloc, Layout, System};
use std::io::Write;
use std::sync::atomic::{AtomicUsize, Ordering};

struct PeakAlloc;

static CURRENT: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for PeakAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            let now = CURRENT.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
            PEAK.fetch_max(now, Ordering::Relaxed);
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        CURRENT.fetch_sub(layout.size(), Ordering::Relaxed);
    }
}

#[global_allocator]
static GLOBAL: PeakAlloc = PeakAlloc;

/// Issue budget for decoding a one-hour file.
const PEAK_BUDGET_BYTES: usize = 300 * 1024 * 1024;

#[test]
fn one_hour_stereo_file_streams_under_300_mb() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("one_hour.wav");
    let rate = 44_100u32;
    let frames = rate as usize * 3600;
    {
        // Streamed to disk too: 635 MB of stereo PCM16 that never sits in memory.
        let f = std::fs::File::create(&path).unwrap();
        let mut w = std::io::BufWriter::with_capacity(1 << 20, f);
        let data_len = (frames * 4) as u32;
        w.write_all(b"RIFF").unwrap();
        w.write_all(&(36 + data_len).to_le_bytes()).unwrap();
        w.write_all(b"WAVEfmt ").unwrap();
        w.write_all(&16u32.to_le_bytes()).unwrap();
        for v in [1u16, 2] {
            w.write_all(&v.to_le_bytes()).unwrap();
        }
        w.write_all(&rate.to_le_bytes()).unwrap();
        w.write_all(&(rate * 4).to_le_bytes()).unwrap();
        for v in [4u16, 16] {
            w.write_all(&v.to_le_bytes()).unwrap();
        }
        w.write_all(b"data").unwrap();
        w.write_all(&data_len.to_le_bytes()).unwrap();
        let mut buf = Vec::with_capacity(4 * 4096);
        for start in (0..frames).step_by(4096) {
            buf.clear();
            for i in start..(start + 4096).min(frames) {
                // A 220 Hz tone with a slow tremolo: cheap, never silent.
                let t = i as f32 / rate as f32;
                let v = 0.3
                    * (2.0 * std::f32::consts::PI * 220.0 * t).sin()
                    * (1.0 + 0.5 * (0.5 * t).sin());
                let s = (v * 32767.0) as i16;
                buf.extend_from_slice(&s.to_le_bytes());
                buf.extend_from_slice(&(-s).to_le_bytes());
            }
            w.write_all(&buf).unwrap();
        }
    }
    let before = CURRENT.load(Ordering::Relaxed);
    PEAK.store(before, Ordering::Relaxed);
    let audio = dancegen_music::load(&path, 15360).unwrap();
    let peak = PEAK.load(Ordering::Relaxed) - before;
    let out_bytes = audio.samples.len() * 4;
    println!(
        "one hour: {} samples out ({:.0} MB), peak heap during load {:.0} MB",
        audio.samples.len(),
        out_bytes as f64 / 1048576.0,
        peak as f64 / 1048576.0
    );
    assert_eq!(audio.samples.len(), 15360 * 3600);
    assert!(peak < PEAK_BUDGET_BYTES, "peak heap {peak} bytes");
}
