//! numpy `.npy` arrays: little-endian, C order, as `numpy.load` expects.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::atomic::{WriteError, write_atomic};

/// Writes a float32 array of `shape` (C order) to `path` atomically.
pub fn write_npy_f32(path: &Path, shape: &[usize], data: &[f32]) -> Result<(), WriteError> {
    let n: usize = shape.iter().product();
    if n != data.len() {
        return Err(WriteError {
            path: path.to_path_buf(),
            reason: format!(
                "shape {shape:?} holds {n} values but {} were given",
                data.len()
            ),
        });
    }
    write_atomic(path, |w| write_npy_f32_to(w, shape, data))
}

/// Writes an `.npy` float32 stream to any writer.
pub fn write_npy_f32_to(w: &mut dyn Write, shape: &[usize], data: &[f32]) -> std::io::Result<()> {
    write_npy_to(w, shape, data)
}

/// Writes an `.npy` stream of any npyz-serialisable element type (`<f4`, `<f8`, `<i8`, …).
fn write_npy_to<T: npyz::Serialize + npyz::AutoSerialize + Copy>(
    w: &mut dyn Write,
    shape: &[usize],
    data: &[T],
) -> std::io::Result<()> {
    let shape_u64: Vec<u64> = shape.iter().map(|&s| s as u64).collect();
    use npyz::WriterBuilder;
    let mut npy = npyz::WriteOptions::<T>::new()
        .default_dtype()
        .shape(&shape_u64)
        .writer(w)
        .begin_nd()?;
    npy.extend(data.iter().copied())?;
    npy.finish()
}

/// Borrowed data for a written array: the element type decides the numpy dtype.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NpyData<'a> {
    /// `<f4`
    F32(&'a [f32]),
    /// `<f8`
    F64(&'a [f64]),
    /// `<i8`
    I64(&'a [i64]),
    /// One unicode string, `<UN` with `N` its length in characters (at least 1), as
    /// `numpy.array('neutral')` stores it: written with shape `[]` (a 0-d array, e.g. AMASS's
    /// `gender`). Not read back by [`parse_npy`], which reads numbers only.
    Str(&'a str),
}

impl NpyData<'_> {
    /// Number of values.
    pub fn len(&self) -> usize {
        match self {
            NpyData::F32(d) => d.len(),
            NpyData::F64(d) => d.len(),
            NpyData::I64(d) => d.len(),
            NpyData::Str(_) => 1,
        }
    }

    /// Whether there are no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The numpy dtype string this data is written as.
    pub fn dtype(&self) -> String {
        match self {
            NpyData::F32(_) => "<f4".into(),
            NpyData::F64(_) => "<f8".into(),
            NpyData::I64(_) => "<i8".into(),
            NpyData::Str(s) => format!("<U{}", s.chars().count().max(1)),
        }
    }
}

/// Writes `data` of `shape` (C order) as an `.npy` stream; a shape whose product differs from
/// the number of values is an `InvalidInput` error. `shape = []` writes a 0-d (scalar) array.
pub fn write_npy_data_to(
    w: &mut dyn Write,
    shape: &[usize],
    data: NpyData<'_>,
) -> std::io::Result<()> {
    let n: usize = shape.iter().product();
    if n != data.len() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!(
                "shape {shape:?} holds {n} values but {} were given",
                data.len()
            ),
        ));
    }
    match data {
        NpyData::F32(d) => write_npy_to(w, shape, d),
        NpyData::F64(d) => write_npy_to(w, shape, d),
        NpyData::I64(d) => write_npy_to(w, shape, d),
        NpyData::Str(s) => write_npy_str_to(w, shape, s, &data.dtype()),
    }
}

/// Writes one string as a `dtype` (`<UN`) array of `shape` (holding one value).
fn write_npy_str_to(
    w: &mut dyn Write,
    shape: &[usize],
    s: &str,
    dtype: &str,
) -> std::io::Result<()> {
    let type_str: npyz::TypeStr = dtype.parse().map_err(std::io::Error::other)?;
    let shape_u64: Vec<u64> = shape.iter().map(|&s| s as u64).collect();
    use npyz::WriterBuilder;
    let mut npy = npyz::WriteOptions::<str>::new()
        .dtype(npyz::DType::Plain(type_str))
        .shape(&shape_u64)
        .writer(w)
        .begin_nd()?;
    npy.push(s)?;
    npy.finish()
}

/// A numpy array read as f64 values, whatever its numeric dtype.
#[derive(Clone, Debug, PartialEq)]
pub struct NpyArray {
    pub shape: Vec<usize>,
    pub data: Vec<f64>,
    /// numpy dtype string, e.g. `<f4`.
    pub dtype: String,
}

/// A `.npy` file that could not be read.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {reason}")]
pub struct ReadError {
    pub path: PathBuf,
    pub reason: String,
}

/// Reads a numeric `.npy` file (float32/64, int8-64, uint8-64, bool) into f64.
pub fn read_npy(path: &Path) -> Result<NpyArray, ReadError> {
    let err = |reason: String| ReadError {
        path: path.to_path_buf(),
        reason,
    };
    let bytes = std::fs::read(path).map_err(|e| err(e.to_string()))?;
    parse_npy(&bytes).map_err(err)
}

/// Parses the bytes of a numeric `.npy` stream (float32/64, int8-64, uint8-64, bool) into f64,
/// C order. The error is a reason without a file name; callers add where the bytes came from.
pub fn parse_npy(bytes: &[u8]) -> Result<NpyArray, String> {
    check_header(bytes)?;
    let npy = npyz::NpyFile::new(bytes).map_err(|e| format!("not a .npy file: {e}"))?;
    let fortran = npy.order() == npyz::Order::Fortran;
    let shape: Vec<usize> = npy.shape().iter().map(|&s| s as usize).collect();
    let dtype = match npy.dtype() {
        npyz::DType::Plain(t) => t.to_string(),
        other => return Err(format!("unsupported dtype {other:?}")),
    };
    macro_rules! conv {
        ($t:ty) => {
            npy.into_vec::<$t>()
                .map_err(|e| e.to_string())?
                .into_iter()
                .map(|v| v as f64)
                .collect()
        };
    }
    let data: Vec<f64> = match dtype.as_str() {
        "<f4" => conv!(f32),
        "<f8" => conv!(f64),
        "<i8" => conv!(i64),
        "<i4" => conv!(i32),
        "<i2" => conv!(i16),
        "|i1" => conv!(i8),
        "<u8" => conv!(u64),
        "<u4" => conv!(u32),
        "<u2" => conv!(u16),
        "|u1" => conv!(u8),
        "|b1" => npy
            .into_vec::<bool>()
            .map_err(|e| e.to_string())?
            .into_iter()
            .map(|v| v as u8 as f64)
            .collect(),
        d => return Err(format!("unsupported dtype {d}")),
    };
    // np.save keeps Fortran order for F-contiguous arrays (e.g. a concatenation of
    // transposes); we always hand out C order.
    let data = if fortran {
        fortran_to_c(&data, &shape)
    } else {
        data
    };
    Ok(NpyArray { shape, data, dtype })
}

/// Longest `.npy` header read, in bytes: numpy's own default limit (`max_header_size`, numpy
/// 1.24+), set for the same reason: the header is a Python literal, and parsing a crafted one
/// can take very long. A header `np.save` writes is under 200 bytes.
pub const NPY_MAX_HEADER_BYTES: usize = 10_000;

/// Deepest bracket nesting (`(`, `[`, `{`) read in a `.npy` header. A numeric array's header
/// nests 2 deep (the dict, its shape tuple); a structured dtype a few more. The header parser
/// (`npyz`'s, a `py_literal` grammar) backtracks exponentially in the nesting depth: a
/// 257-byte file with 28 nested `[` took over two minutes (found by `fuzz/`'s `npy` target).
pub const NPY_MAX_HEADER_NESTING: usize = 8;

/// Refuses a header longer than [`NPY_MAX_HEADER_BYTES`] or nested deeper than
/// [`NPY_MAX_HEADER_NESTING`] before it is parsed. Bytes too short to hold a header are left
/// to the parser, which says what is missing.
fn check_header(bytes: &[u8]) -> Result<(), String> {
    let Some(rest) = bytes.strip_prefix(b"\x93NUMPY") else {
        return Ok(());
    };
    let (len, header) = match rest {
        [1, _, a, b, h @ ..] => (u16::from_le_bytes([*a, *b]) as usize, h),
        [2 | 3, _, a, b, c, d, h @ ..] => (u32::from_le_bytes([*a, *b, *c, *d]) as usize, h),
        _ => return Ok(()),
    };
    if len > NPY_MAX_HEADER_BYTES {
        return Err(format!(
            "not a .npy file dancegen reads: its header is {len} bytes (at most \
             {NPY_MAX_HEADER_BYTES})"
        ));
    }
    let header = &header[..len.min(header.len())];
    let (mut depth, mut deepest, mut quote) = (0usize, 0usize, None::<u8>);
    for &b in header {
        match (quote, b) {
            (Some(q), _) if b == q => quote = None,
            (Some(_), _) => {}
            (None, b'\'' | b'"') => quote = Some(b),
            (None, b'(' | b'[' | b'{') => {
                depth += 1;
                deepest = deepest.max(depth);
            }
            (None, b')' | b']' | b'}') => depth = depth.saturating_sub(1),
            _ => {}
        }
    }
    if deepest > NPY_MAX_HEADER_NESTING {
        return Err(format!(
            "not a .npy file dancegen reads: its header nests {deepest} brackets deep (at \
             most {NPY_MAX_HEADER_NESTING})"
        ));
    }
    Ok(())
}

/// Longest string [`parse_npy_text`] reads, in characters: a record, not a data set.
pub const NPY_TEXT_MAX_CHARS: usize = 1 << 16;

/// Parses a 0-d unicode `.npy` stream (`<UN`, UTF-32LE code points, trailing NULs dropped as
/// numpy drops them) into its string.
pub fn parse_npy_text(bytes: &[u8]) -> Result<String, String> {
    let rest = bytes
        .strip_prefix(b"\x93NUMPY")
        .ok_or("not a .npy file: no magic string")?;
    let (major, rest) = match rest {
        [major, _minor, rest @ ..] => (*major, rest),
        _ => return Err("not a .npy file: truncated header".into()),
    };
    let (len, rest) = match (major, rest) {
        (1, [a, b, rest @ ..]) => (usize::from(u16::from_le_bytes([*a, *b])), rest),
        (2 | 3, [a, b, c, d, rest @ ..]) => (u32::from_le_bytes([*a, *b, *c, *d]) as usize, rest),
        _ => return Err(format!("unsupported .npy version {major}")),
    };
    if len > rest.len() {
        return Err("not a .npy file: header longer than the file".into());
    }
    let header = std::str::from_utf8(&rest[..len]).map_err(|_| "header is not text")?;
    let data = &rest[len..];
    let chars: usize = header
        .split("'descr':")
        .nth(1)
        .and_then(|d| d.trim_start().strip_prefix("'<U"))
        .and_then(|d| d.split('\'').next())
        .and_then(|n| n.parse().ok())
        .ok_or_else(|| format!("not a unicode string array (header {})", header.trim()))?;
    if !header.contains("'shape': ()") {
        return Err(format!("not one string: header {}", header.trim()));
    }
    if chars > NPY_TEXT_MAX_CHARS {
        return Err(format!(
            "a string of {chars} characters, over the {NPY_TEXT_MAX_CHARS} read"
        ));
    }
    if data.len() < 4 * chars {
        return Err(format!(
            "{} data bytes for a string of {chars} characters",
            data.len()
        ));
    }
    data[..4 * chars]
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .take_while(|&c| c != 0)
        .map(|c| char::from_u32(c).ok_or_else(|| format!("{c:#x} is not a character")))
        .collect()
}

/// Reorders a Fortran-order (column-major) buffer of `shape` to C order.
pub fn fortran_to_c(data: &[f64], shape: &[usize]) -> Vec<f64> {
    let nd = shape.len();
    let mut idx = vec![0usize; nd];
    let mut out = vec![0.0; data.len()];
    for (ci, o) in out.iter_mut().enumerate() {
        let mut rem = ci;
        for d in (0..nd).rev() {
            idx[d] = rem % shape[d];
            rem /= shape[d];
        }
        let mut fi = 0;
        for d in (0..nd).rev() {
            fi = fi * shape[d] + idx[d];
        }
        *o = data[fi];
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_f32() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.npy");
        let data: Vec<f32> = (0..6).map(|i| i as f32 * 0.5).collect();
        write_npy_f32(&p, &[2, 3], &data).unwrap();
        let a = read_npy(&p).unwrap();
        assert_eq!(a.shape, vec![2, 3]);
        assert_eq!(a.dtype, "<f4");
        assert_eq!(a.data, data.iter().map(|&v| v as f64).collect::<Vec<_>>());
        let raw = std::fs::read(&p).unwrap();
        assert_eq!(&raw[..6], b"\x93NUMPY");
        // numpy aligns the data start to 64 bytes; 6 float32 follow the header.
        assert_eq!((raw.len() - 24) % 64, 0);
    }

    #[test]
    fn fortran_order_is_reordered() {
        // 2x3 matrix [[0,1,2],[3,4,5]] stored column-major: 0,3,1,4,2,5.
        let f = [0.0, 3.0, 1.0, 4.0, 2.0, 5.0];
        assert_eq!(
            fortran_to_c(&f, &[2, 3]),
            vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0]
        );
    }

    #[test]
    fn shape_mismatch_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        assert!(write_npy_f32(&dir.path().join("a.npy"), &[2, 2], &[1.0]).is_err());
    }

    #[test]
    fn a_string_is_a_0d_unicode_array() {
        let mut buf = Vec::new();
        write_npy_data_to(&mut buf, &[], NpyData::Str("neutral")).unwrap();
        let header = String::from_utf8_lossy(&buf[10..buf.len() - 28]).into_owned();
        assert!(
            header.contains("'descr': '<U7'") && header.contains("'shape': ()"),
            "{header}"
        );
        // UTF-32LE code points, aligned as numpy aligns data.
        let data = &buf[buf.len() - 28..];
        let text: String = data
            .chunks_exact(4)
            .map(|c| char::from_u32(u32::from_le_bytes([c[0], c[1], c[2], c[3]])).unwrap())
            .collect();
        assert_eq!(text, "neutral");
        assert_eq!((buf.len() - 28) % 64, 0);
        assert_eq!(NpyData::Str("neutral").dtype(), "<U7");
        assert!(write_npy_data_to(&mut Vec::new(), &[2], NpyData::Str("x")).is_err());
    }

    #[test]
    fn a_written_string_reads_back_and_bad_ones_are_refused() {
        for text in ["neutral", "{\"song\": \"a é ♪.ogg\"}", ""] {
            let mut buf = Vec::new();
            write_npy_data_to(&mut buf, &[], NpyData::Str(text)).unwrap();
            assert_eq!(parse_npy_text(&buf).unwrap(), text);
        }
        let mut numbers = Vec::new();
        write_npy_f32_to(&mut numbers, &[2], &[1.0, 2.0]).unwrap();
        assert!(
            parse_npy_text(&numbers)
                .unwrap_err()
                .contains("not a unicode")
        );
        let mut short = Vec::new();
        write_npy_data_to(&mut short, &[], NpyData::Str("neutral")).unwrap();
        short.truncate(short.len() - 8);
        assert!(parse_npy_text(&short).unwrap_err().contains("data bytes"));
        assert!(parse_npy_text(b"\x93NUMPY\x01").is_err());
        assert!(parse_npy_text(b"junk").is_err());
    }

    #[test]
    fn garbage_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("g.npy");
        std::fs::write(&p, b"not numpy").unwrap();
        assert!(read_npy(&p).unwrap_err().to_string().contains("not a .npy"));
    }
}
