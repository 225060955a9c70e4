use std::time::Instant;
fn main() {
    let p = std::env::args().nth(1).unwrap();
    let path = std::path::Path::new(&p);
    for _ in 0..3 {
        let t = Instant::now();
        let (y, sr) = dancegen_music::decode::decode_mono(path).unwrap();
        let t1 = t.elapsed();
        let a = dancegen_music::resample::resample_hq(&y, sr as f64, 15360.0, false).unwrap();
        let t2 = t.elapsed();
        let b = dancegen_music::resample::resample_hq(&y, sr as f64, 22050.0, false).unwrap();
        let t3 = t.elapsed();
        let m = dancegen_music::mel::mel_power(&a, 15360.0, 512);
        let t4 = t.elapsed();
        println!(
            "decode {:?} rs15360 {:?} rs22050 {:?} mel {:?} ({} {} {})",
            t1,
            t2 - t1,
            t3 - t2,
            t4 - t3,
            y.len(),
            b.len(),
            m.rows
        );
    }
}
