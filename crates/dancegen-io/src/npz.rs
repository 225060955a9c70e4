//! numpy `.npz` archives: a zip file of `<name>.npy` members, as `numpy.savez` (stored) and
//! `numpy.savez_compressed` (deflate) write them.
//!
//! Reading decompresses into memory under a size budget ([`NPZ_MAX_TOTAL_BYTES`] by default) so
//! a crafted archive (a "zip bomb") cannot exhaust memory: a member whose declared size exceeds
//! what is left of the budget is refused before it is decompressed, and decompression stops as
//! soon as the real output passes the budget, whatever the archive claims.
//!
//! Writing produces a stored (uncompressed) archive like `numpy.savez`, through
//! [`write_atomic`], so `numpy.load` reads it and an interrupted write never leaves a broken file.

use std::io::{Cursor, Read, Write};
use std::path::Path;

use crate::atomic::{WriteError, write_atomic};
use crate::npy::{NpyArray, NpyData, ReadError, parse_npy, write_npy_data_to};

/// Default cap on the total uncompressed size of the members read from one archive: 4 GiB.
pub const NPZ_MAX_TOTAL_BYTES: u64 = 4 << 30;

/// Reads every member of a `.npz` file, in archive order, names without the `.npy` suffix.
///
/// Every member must be a numeric `.npy` array (see [`parse_npy`]); use [`read_npz_members`]
/// to pick members and skip others (e.g. the string `gender` array of AMASS files).
pub fn read_npz(path: &Path) -> Result<Vec<(String, NpyArray)>, ReadError> {
    read_npz_with(path, None, NPZ_MAX_TOTAL_BYTES)
}

/// Reads only the members named in `wanted` (names without `.npy`), in archive order. Members
/// not in `wanted` are not decompressed nor parsed; wanted names absent from the archive are
/// simply absent from the result.
pub fn read_npz_members(
    path: &Path,
    wanted: &[&str],
) -> Result<Vec<(String, NpyArray)>, ReadError> {
    read_npz_with(path, Some(wanted), NPZ_MAX_TOTAL_BYTES)
}

/// [`read_npz`] / [`read_npz_members`] with an explicit budget for the total uncompressed bytes.
pub fn read_npz_with(
    path: &Path,
    wanted: Option<&[&str]>,
    max_total_bytes: u64,
) -> Result<Vec<(String, NpyArray)>, ReadError> {
    let mut out = Vec::new();
    each_member(path, wanted, max_total_bytes, |name, bytes| {
        out.push((name, parse_npy(bytes)?));
        Ok(())
    })?;
    Ok(out)
}

/// The one string of the 0-d unicode member `name` (as [`crate::npy::NpyData::Str`] writes
/// and `numpy.savez` stores a Python `str`), or `None` when the archive has no such member.
pub fn read_npz_text(path: &Path, name: &str) -> Result<Option<String>, ReadError> {
    let mut found = None;
    each_member(path, Some(&[name]), NPZ_MAX_TOTAL_BYTES, |_, bytes| {
        found = Some(crate::npy::parse_npy_text(bytes)?);
        Ok(())
    })?;
    Ok(found)
}

/// Calls `f` with the name and bytes of every wanted `.npy` member, within the byte budget.
fn each_member(
    path: &Path,
    wanted: Option<&[&str]>,
    max_total_bytes: u64,
    mut f: impl FnMut(String, &[u8]) -> Result<(), String>,
) -> Result<(), ReadError> {
    let err = |reason: String| ReadError {
        path: path.to_path_buf(),
        reason,
    };
    let file = std::fs::File::open(path).map_err(|e| err(e.to_string()))?;
    let mut zip = zip::ZipArchive::new(std::io::BufReader::new(file))
        .map_err(|e| err(format!("not a .npz (zip) file: {e}")))?;
    let mut budget = max_total_bytes;
    for i in 0..zip.len() {
        let mut member = zip
            .by_index(i)
            .map_err(|e| err(format!("zip member #{i}: {e}")))?;
        if member.is_dir() {
            continue;
        }
        let full = member.name().to_string();
        let merr = |reason: String| err(format!("member {full:?}: {reason}"));
        let name = full.strip_suffix(".npy").unwrap_or(&full).to_string();
        if let Some(w) = wanted
            && !w.contains(&name.as_str())
        {
            continue;
        }
        if !full.ends_with(".npy") {
            return Err(merr("not an .npy member".into()));
        }
        let declared = member.size();
        if declared > budget {
            return Err(merr(format!(
                "declares {declared} uncompressed bytes, over the remaining read budget of \
                 {budget} bytes (limit {max_total_bytes} bytes per archive)"
            )));
        }
        // Never trust the declared size: read at most one byte past the budget.
        let mut bytes = Vec::with_capacity(declared.min(1 << 26) as usize);
        (&mut member)
            .take(budget + 1)
            .read_to_end(&mut bytes)
            .map_err(|e| merr(format!("cannot decompress: {e}")))?;
        let got = bytes.len() as u64;
        if got > budget {
            return Err(merr(format!(
                "decompresses to more than the remaining read budget of {budget} bytes \
                 (limit {max_total_bytes} bytes per archive)"
            )));
        }
        if got != declared {
            return Err(merr(format!(
                "decompressed to {got} bytes but the archive declares {declared}"
            )));
        }
        budget -= got;
        f(name, &bytes).map_err(merr)?;
    }
    Ok(())
}

/// Writes a stored (uncompressed) `.npz` like `numpy.savez`: one `<name>.npy` member per entry
/// `(name, shape, data)`, in order. `shape = &[]` writes a 0-d (scalar) array. Names must be
/// unique, non-empty and contain no `/`; each shape must hold exactly its data.
pub fn write_npz(path: &Path, members: &[(&str, &[usize], NpyData<'_>)]) -> Result<(), WriteError> {
    let err = |reason: String| WriteError {
        path: path.to_path_buf(),
        reason,
    };
    for (i, (name, shape, data)) in members.iter().enumerate() {
        if name.is_empty() || name.contains('/') || name.contains('\\') {
            return Err(err(format!("invalid member name {name:?}")));
        }
        if members[..i].iter().any(|(n, _, _)| n == name) {
            return Err(err(format!("duplicate member name {name:?}")));
        }
        let n: usize = shape.iter().product();
        if n != data.len() {
            return Err(err(format!(
                "member {name:?}: shape {shape:?} holds {n} values but {} were given",
                data.len()
            )));
        }
    }
    let bytes = npz_bytes(members).map_err(|e| err(e.to_string()))?;
    write_atomic(path, |w| w.write_all(&bytes))
}

/// Builds the archive in memory (zip needs a seekable writer; `write_atomic` gives a stream).
fn npz_bytes(members: &[(&str, &[usize], NpyData<'_>)]) -> std::io::Result<Vec<u8>> {
    let mut zip = zip::ZipWriter::new(Cursor::new(Vec::new()));
    for (name, shape, data) in members {
        let mut npy = Vec::new();
        write_npy_data_to(&mut npy, shape, *data)?;
        let options = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Stored)
            .large_file(npy.len() as u64 >= u32::MAX as u64);
        zip.start_file(format!("{name}.npy"), options)
            .map_err(std::io::Error::other)?;
        zip.write_all(&npy)?;
    }
    Ok(zip.finish().map_err(std::io::Error::other)?.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::npy::write_npy_f32;

    fn get<'a>(members: &'a [(String, NpyArray)], name: &str) -> &'a NpyArray {
        &members.iter().find(|(n, _)| n == name).unwrap().1
    }

    #[test]
    fn round_trip_f32_f64_i64_and_scalar() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.npz");
        let a: Vec<f32> = (0..6).map(|i| i as f32 * 0.25 - 1.0).collect();
        let b: Vec<f64> = vec![std::f64::consts::PI, -1e-300, 1e300, 0.1];
        let c: Vec<i64> = vec![-3, 0, 1 << 40];
        let fps = [59.94_f64];
        write_npz(
            &p,
            &[
                ("poses", &[2, 3], NpyData::F32(&a)),
                ("trans", &[4, 1], NpyData::F64(&b)),
                ("ids", &[3], NpyData::I64(&c)),
                ("mocap_framerate", &[], NpyData::F64(&fps)),
            ],
        )
        .unwrap();
        let m = read_npz(&p).unwrap();
        let names: Vec<&str> = m.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["poses", "trans", "ids", "mocap_framerate"]);
        let poses = get(&m, "poses");
        assert_eq!(
            (poses.shape.as_slice(), poses.dtype.as_str()),
            (&[2, 3][..], "<f4")
        );
        assert_eq!(poses.data, a.iter().map(|&v| v as f64).collect::<Vec<_>>());
        let trans = get(&m, "trans");
        assert_eq!(
            (trans.shape.as_slice(), trans.dtype.as_str()),
            (&[4, 1][..], "<f8")
        );
        assert_eq!(trans.data, b);
        let ids = get(&m, "ids");
        assert_eq!(ids.dtype, "<i8");
        assert_eq!(ids.data, c.iter().map(|&v| v as f64).collect::<Vec<_>>());
        let f = get(&m, "mocap_framerate");
        assert!(f.shape.is_empty());
        assert_eq!(f.data, fps);

        let only = read_npz_members(&p, &["trans", "missing"]).unwrap();
        assert_eq!(only.len(), 1);
        assert_eq!(only[0].0, "trans");
    }

    #[test]
    fn written_archive_is_stored_with_npy_members() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.npz");
        write_npz(&p, &[("x", &[2], NpyData::F32(&[1.0, 2.0]))]).unwrap();
        let mut z = zip::ZipArchive::new(std::fs::File::open(&p).unwrap()).unwrap();
        let f = z.by_index(0).unwrap();
        assert_eq!(f.name(), "x.npy");
        assert_eq!(f.compression(), zip::CompressionMethod::Stored);
    }

    #[test]
    fn write_errors_name_the_member() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.npz");
        let e = write_npz(&p, &[("x", &[3], NpyData::F32(&[1.0]))]).unwrap_err();
        assert!(e.to_string().contains("\"x\""), "{e}");
        let e = write_npz(
            &p,
            &[
                ("x", &[1], NpyData::F32(&[1.0])),
                ("x", &[1], NpyData::F32(&[1.0])),
            ],
        )
        .unwrap_err();
        assert!(e.to_string().contains("duplicate"), "{e}");
        assert!(!p.exists());
    }

    /// Runs python3's `zipfile` (always available with python3, unlike numpy) to build an
    /// archive from `.npy` files. Returns false when python3 is missing.
    fn python_zip(out: &Path, files: &[(&str, &Path)], compression: &str) -> bool {
        let mut script = format!(
            "import zipfile\nwith zipfile.ZipFile({:?}, 'w', compression=zipfile.{compression}) as z:\n",
            out.to_str().unwrap()
        );
        for (name, f) in files {
            script += &format!("    z.write({:?}, arcname={name:?})\n", f.to_str().unwrap());
        }
        match std::process::Command::new("python3")
            .arg("-c")
            .arg(&script)
            .status()
        {
            Ok(s) => {
                assert!(s.success(), "python3 zipfile failed");
                true
            }
            Err(_) => false,
        }
    }

    #[test]
    fn reads_python_zipfile_archives_stored_and_deflated() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("a.npy");
        let b = dir.path().join("b.npy");
        let av: Vec<f32> = (0..1000).map(|i| (i % 7) as f32).collect();
        write_npy_f32(&a, &[100, 10], &av).unwrap();
        write_npy_f32(&b, &[], &[30.0]).unwrap();
        for compression in ["ZIP_STORED", "ZIP_DEFLATED"] {
            let z = dir.path().join(format!("{compression}.npz"));
            if !python_zip(&z, &[("poses.npy", &a), ("fps.npy", &b)], compression) {
                eprintln!("python3 not found; skipping");
                return;
            }
            let m = read_npz(&z).unwrap();
            assert_eq!(m.len(), 2);
            assert_eq!(get(&m, "poses").shape, vec![100, 10]);
            assert_eq!(
                get(&m, "poses").data,
                av.iter().map(|&v| v as f64).collect::<Vec<_>>()
            );
            assert_eq!(get(&m, "fps").data, vec![30.0]);
        }
    }

    #[test]
    fn budget_refuses_large_members_and_deflate_bombs() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("zeros.npy");
        // 4 MB of zeros deflates to a few kB.
        write_npy_f32(&a, &[1 << 20], &vec![0.0; 1 << 20]).unwrap();
        let z = dir.path().join("bomb.npz");
        if !python_zip(&z, &[("zeros.npy", &a)], "ZIP_DEFLATED") {
            return;
        }
        assert!(std::fs::metadata(&z).unwrap().len() < 100_000);
        let e = read_npz_with(&z, None, 1 << 20).unwrap_err().to_string();
        assert!(e.contains("zeros.npy") && e.contains("budget"), "{e}");
        assert!(e.contains("bomb.npz"), "{e}");
        assert_eq!(read_npz_with(&z, None, 8 << 20).unwrap().len(), 1);

        // An archive lying about its uncompressed size: patch the declared sizes in the local
        // and central headers down to 16 bytes; decompression must still be cut off.
        let mut raw = std::fs::read(&z).unwrap();
        let real = (4u32 << 20) + 128;
        let declared = real.to_le_bytes();
        let mut patched = 0;
        for i in 0..raw.len() - 4 {
            if raw[i..i + 4] == declared {
                raw[i..i + 4].copy_from_slice(&16u32.to_le_bytes());
                patched += 1;
            }
        }
        assert_eq!(patched, 2, "local + central uncompressed size");
        let liar = dir.path().join("liar.npz");
        std::fs::write(&liar, &raw).unwrap();
        let e = read_npz_with(&liar, None, 1 << 20).unwrap_err().to_string();
        assert!(e.contains("zeros.npy"), "{e}");
    }

    #[test]
    fn bad_members_and_files_are_clear_errors() {
        let dir = tempfile::tempdir().unwrap();
        let g = dir.path().join("g.npz");
        std::fs::write(&g, b"not a zip").unwrap();
        let e = read_npz(&g).unwrap_err().to_string();
        assert!(e.contains("g.npz") && e.contains("not a .npz"), "{e}");

        let junk = dir.path().join("junk.npy");
        std::fs::write(&junk, b"garbage bytes").unwrap();
        let z = dir.path().join("j.npz");
        if !python_zip(&z, &[("junk.npy", &junk)], "ZIP_STORED") {
            return;
        }
        let e = read_npz(&z).unwrap_err().to_string();
        assert!(e.contains("j.npz") && e.contains("junk.npy"), "{e}");
        // Skipped members are not parsed.
        assert!(read_npz_members(&z, &["other"]).unwrap().is_empty());
    }
}
