//! `dancegen.io`: every motion `dancegen convert` reads, as joints and (where the file has
//! them) SMPL rotations; every format it writes; SMPL forward kinematics.

use std::path::PathBuf;

use dancegen_formats::dispatch::{
    ConvertOptions, LoadOptions, LoadedMotion, NpzStyle, check_source_fps, convert_motion,
    joint_positions, load_motion_file_with, save_motion_file,
};
use dancegen_motion::repr::motion::SmplMotion;
use pyo3::prelude::*;

use crate::arrays::{check_finite, f32_values, to_numpy};
use crate::fail;

/// A motion as `dancegen convert` holds it: SMPL 24 rotations and root path (one dancer or a
/// group), a BVH with its own skeleton, or joint positions only.
#[pyclass(module = "dancegen.io", frozen)]
pub struct Motion {
    inner: LoadedMotion,
    /// Where it came from, for messages (`<array>` for one built from arrays).
    origin: PathBuf,
}

impl Motion {
    fn smpl_parts(&self) -> Option<Vec<&SmplMotion>> {
        match &self.inner {
            LoadedMotion::Smpl(s) => Some(vec![s]),
            LoadedMotion::Group(g) => Some(g.iter().collect()),
            _ => None,
        }
    }

    /// `(T, 24, 3)` per dancer stacked to `(N, T, ...)` for a group, from `part`.
    fn smpl_array<'py>(
        &self,
        py: Python<'py>,
        width: usize,
        part: fn(&SmplMotion) -> &[f32],
    ) -> PyResult<Option<Bound<'py, PyAny>>> {
        let Some(parts) = self.smpl_parts() else {
            return Ok(None);
        };
        let frames = parts.first().map_or(0, |s| s.frames());
        let data: Vec<f32> = parts.iter().flat_map(|s| part(s).iter().copied()).collect();
        let mut shape = vec![frames];
        if width == 72 {
            shape.extend([24, 3]);
        } else {
            shape.push(width);
        }
        if matches!(self.inner, LoadedMotion::Group(_)) {
            shape.insert(0, parts.len());
        }
        to_numpy(py, &shape, data).map(Some)
    }
}

fn npz_style(name: &str) -> PyResult<NpzStyle> {
    match name {
        "amass" => Ok(NpzStyle::Amass),
        "edge" => Ok(NpzStyle::Edge),
        other => Err(fail(format!("npz_style '{other}': choose amass or edge"))),
    }
}

/// `convert`'s options from its keyword arguments.
fn convert_options(
    fps: Option<f32>,
    to: Option<&str>,
    dancer: Option<usize>,
    rig: &str,
    npz_style_name: &str,
) -> PyResult<ConvertOptions> {
    let to_smpl24 = match to {
        None => false,
        Some("smpl24") => true,
        Some(other) => return Err(fail(format!("to '{other}': the one target is smpl24"))),
    };
    if let Some(f) = fps
        && !(f.is_finite() && f > 0.0)
    {
        return Err(fail(format!("fps must be a positive number, got {f}")));
    }
    Ok(ConvertOptions {
        fps,
        to_smpl24,
        dancer,
        npz_style: npz_style(npz_style_name)?,
        npz_record: None,
        rig: dancegen_generate::flags::values::parse_rig(rig).map_err(fail)?,
    })
}

#[pymethods]
impl Motion {
    /// Frames per second.
    #[getter]
    fn fps(&self) -> f32 {
        self.inner.fps()
    }

    /// What it holds: "SMPL 24 motion", "group motion", "BVH motion" or "joint positions".
    #[getter]
    fn kind(&self) -> &'static str {
        self.inner.kind()
    }

    /// Number of dancers.
    #[getter]
    fn dancers(&self) -> usize {
        match &self.inner {
            LoadedMotion::Group(g) => g.len(),
            LoadedMotion::Joints { dancers, .. } => *dancers,
            _ => 1,
        }
    }

    /// World joint positions, float32: `(T, J, 3)`, or `(N, T, J, 3)` for a group (metres and
    /// Y-up for SMPL motion; a BVH's own units and joints).
    #[getter]
    fn joints<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let (shape, data) = py
            .detach(|| joint_positions(&self.origin, &self.inner))
            .map_err(fail)?;
        to_numpy(py, &shape, data)
    }

    /// SMPL local rotations as axis-angle, float32 `(T, 24, 3)` (`(N, T, 24, 3)` for a
    /// group); `None` for a BVH or joint positions.
    #[getter]
    fn poses<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.smpl_array(py, 72, |s| &s.poses)
    }

    /// The SMPL pelvis path, metres, Y-up, float32 `(T, 3)` (`(N, T, 3)` for a group); `None`
    /// for a BVH or joint positions.
    #[getter]
    fn trans<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.smpl_array(py, 3, |s| &s.trans)
    }

    /// The motion `dancegen convert` would make with these options: `fps` resamples, `to`
    /// "smpl24" retargets a BVH to SMPL 24, `dancer` picks one dancer of a group.
    #[pyo3(signature = (fps=None, to=None, dancer=None))]
    fn convert(
        &self,
        py: Python<'_>,
        fps: Option<f32>,
        to: Option<&str>,
        dancer: Option<usize>,
    ) -> PyResult<Motion> {
        let opts = convert_options(fps, to, dancer, "smpl", "amass")?;
        let inner = py
            .detach(|| convert_motion(&self.origin, self.inner.clone(), &opts))
            .map_err(fail)?;
        Ok(Motion {
            inner,
            origin: self.origin.clone(),
        })
    }

    /// Writes the motion as `dancegen convert` writes it, in the format of `path`'s
    /// extension: .bvh .glb .fbx .npz .npy .json. `rig` names the bones of .bvh/.glb/.fbx
    /// (smpl, mixamo, ue5, vrm); `npz_style` is amass or edge; `fps`, `to` and `dancer` as in
    /// [`Motion::convert`]. The file appears whole or not at all.
    #[pyo3(signature = (path, rig="smpl", npz_style="amass", fps=None, to=None, dancer=None))]
    #[allow(clippy::too_many_arguments)]
    fn save(
        &self,
        py: Python<'_>,
        path: PathBuf,
        rig: &str,
        npz_style: &str,
        fps: Option<f32>,
        to: Option<&str>,
        dancer: Option<usize>,
    ) -> PyResult<()> {
        let opts = convert_options(fps, to, dancer, rig, npz_style)?;
        py.detach(|| {
            let converted = convert_motion(&self.origin, self.inner.clone(), &opts)?;
            save_motion_file(&path, &converted, &opts)
        })
        .map_err(fail)
    }

    fn __repr__(&self) -> String {
        let frames = match &self.inner {
            LoadedMotion::Smpl(s) => s.frames(),
            LoadedMotion::Group(g) => g.first().map_or(0, |s| s.frames()),
            LoadedMotion::Bvh(b) => b.frames,
            LoadedMotion::Joints {
                dancers,
                joints,
                positions,
                ..
            } => positions.len() / (dancers * joints * 3).max(1),
        };
        format!(
            "Motion({}, {} frames at {} fps, {} dancer(s), from {})",
            self.inner.kind(),
            frames,
            self.inner.fps(),
            self.dancers(),
            self.origin.display()
        )
    }
}

/// Reads any motion `dancegen convert` reads (AIST++ .pkl, SMPL/AMASS/EDGE .npz, FineDance and
/// joints .npy, BVH, group files, dancegen's outputs). `source_fps`: the rate it was captured
/// at, whatever its header says.
#[pyfunction]
#[pyo3(signature = (path, source_fps=None))]
pub fn read(py: Python<'_>, path: PathBuf, source_fps: Option<f64>) -> PyResult<Motion> {
    if let Some(f) = source_fps {
        check_source_fps(f).map_err(|e| fail(format!("source_fps: {e}")))?;
    }
    let opts = LoadOptions {
        source_fps,
        rate_hint: "source_fps=N",
    };
    let inner = py
        .detach(|| load_motion_file_with(&path, &opts))
        .map_err(fail)?;
    Ok(Motion {
        inner,
        origin: path,
    })
}

/// The SMPL motions of `poses` `(T, 24, 3)` or `(T, 72)` axis-angle and `trans` `(T, 3)`
/// (a group: `(N, T, 24, 3)` and `(N, T, 3)`).
fn smpl_motions(
    poses: &Bound<'_, PyAny>,
    trans: &Bound<'_, PyAny>,
    fps: f32,
) -> PyResult<Vec<SmplMotion>> {
    let (ps, pd) = f32_values(poses, "poses")?;
    let (ts, td) = f32_values(trans, "trans")?;
    check_finite("poses", &pd)?;
    check_finite("trans", &td)?;
    let (n, t) = match (ps.as_slice(), ts.as_slice()) {
        ([t, 24, 3] | [t, 72], [tt, 3]) if t == tt => (1, *t),
        ([n, t, 24, 3] | [n, t, 72], [nn, tt, 3]) if n == nn && t == tt => (*n, *t),
        _ => {
            return Err(fail(format!(
                "poses {ps:?} and trans {ts:?}: expected poses (T, 24, 3) or (T, 72) with \
                 trans (T, 3), or a group (N, T, 24, 3) with (N, T, 3)"
            )));
        }
    };
    if n == 0 || t == 0 {
        return Err(fail("poses and trans hold no frames"));
    }
    if !(fps.is_finite() && fps > 0.0) {
        return Err(fail(format!("fps must be a positive number, got {fps}")));
    }
    pd.chunks_exact(t * 72)
        .zip(td.chunks_exact(t * 3))
        .map(|(p, tr)| SmplMotion::new(fps, p.to_vec(), tr.to_vec()).map_err(fail))
        .collect()
}

/// A motion from SMPL arrays: `poses` axis-angle `(T, 24, 3)` or `(T, 72)`, `trans` the
/// pelvis path `(T, 3)`, metres, Y-up (a group: `(N, T, 24, 3)` and `(N, T, 3)`).
#[pyfunction]
#[pyo3(signature = (poses, trans, fps=30.0))]
pub fn smpl(poses: &Bound<'_, PyAny>, trans: &Bound<'_, PyAny>, fps: f32) -> PyResult<Motion> {
    let mut m = smpl_motions(poses, trans, fps)?;
    let inner = if m.len() == 1 {
        LoadedMotion::Smpl(m.remove(0))
    } else {
        LoadedMotion::Group(m)
    };
    Ok(Motion {
        inner,
        origin: PathBuf::from("<arrays>"),
    })
}

/// A motion of joint positions only, `(T, J, 3)` or `(N, T, J, 3)` (it writes `.npy`; the
/// other formats need rotations).
#[pyfunction]
#[pyo3(signature = (positions, fps=30.0))]
pub fn joints(positions: &Bound<'_, PyAny>, fps: f32) -> PyResult<Motion> {
    let (shape, data) = f32_values(positions, "positions")?;
    check_finite("positions", &data)?;
    let (dancers, joints) = match shape.as_slice() {
        [t, j, 3] if *t > 0 && *j > 0 => (1, *j),
        [n, t, j, 3] if *n > 0 && *t > 0 && *j > 0 => (*n, *j),
        s => {
            return Err(fail(format!(
                "positions {s:?}: expected (T, J, 3) or (N, T, J, 3)"
            )));
        }
    };
    if !(fps.is_finite() && fps > 0.0) {
        return Err(fail(format!("fps must be a positive number, got {fps}")));
    }
    Ok(Motion {
        inner: LoadedMotion::Joints {
            fps,
            dancers,
            joints,
            positions: data,
        },
        origin: PathBuf::from("<array>"),
    })
}

/// SMPL 24 forward kinematics: world joint positions `(T, 24, 3)` (or `(N, T, 24, 3)`) of
/// `poses` and `trans` on the SMPL skeleton dancegen uses everywhere (metres, Y-up).
#[pyfunction]
pub fn smpl_fk<'py>(
    py: Python<'py>,
    poses: &Bound<'py, PyAny>,
    trans: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let motions = smpl_motions(poses, trans, 30.0)?;
    let group = f32_values(poses, "poses")?.0.len() == 4 || motions.len() > 1;
    let frames = motions[0].frames();
    let data = py
        .detach(|| {
            let mut all = Vec::with_capacity(motions.len() * frames * 72);
            for m in &motions {
                all.extend(m.joints_world()?);
            }
            Ok::<_, dancegen_motion::repr::ReprError>(all)
        })
        .map_err(fail)?;
    let mut shape = vec![frames, 24, 3];
    if group {
        shape.insert(0, motions.len());
    }
    to_numpy(py, &shape, data)
}
