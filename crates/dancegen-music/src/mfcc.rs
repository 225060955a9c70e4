//! MFCC: the first `n_mfcc` rows of an orthonormal DCT-II of the mel dB spectrogram
//! (`librosa.feature.mfcc`, no liftering).

use crate::stft::FrameMatrix;

/// Orthonormal DCT-II basis, `n_out × n_in` (scipy `dct(type=2, norm='ortho')`).
pub fn dct2_ortho_basis(n_in: usize, n_out: usize) -> Vec<f64> {
    let n = n_in as f64;
    let mut b = Vec::with_capacity(n_in * n_out);
    for k in 0..n_out {
        let scale = if k == 0 {
            (1.0 / n).sqrt()
        } else {
            (2.0 / n).sqrt()
        };
        for i in 0..n_in {
            let arg = std::f64::consts::PI * k as f64 * (2 * i + 1) as f64 / (2.0 * n);
            b.push(scale * arg.cos());
        }
    }
    b
}

/// MFCCs (frames × `n_mfcc`) from a mel dB spectrogram (frames × mels).
pub fn mfcc_from_mel_db(mel_db: &FrameMatrix, n_mfcc: usize) -> FrameMatrix {
    let n_mels = mel_db.cols;
    let basis = dct2_ortho_basis(n_mels, n_mfcc);
    let mut out = FrameMatrix::zeros(mel_db.rows, n_mfcc);
    out.par_row_blocks(512, |frames, rows| {
        for (t, row) in frames.zip(rows.chunks_exact_mut(n_mfcc)) {
            let x = mel_db.row(t);
            for (k, o) in row.iter_mut().enumerate() {
                let b = &basis[k * n_mels..(k + 1) * n_mels];
                *o = x.iter().zip(b).map(|(&a, &w)| a as f64 * w).sum::<f64>() as f32;
            }
        }
    });
    out
}
