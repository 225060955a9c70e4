//! `dancegen.generate`: a dance from a song with `dancegen generate`'s options by name, and
//! the `Dance` it returns (joints as the CLI's `.npy`, `save` to any output format, each file
//! the one `dancegen generate -o` writes for the same song, options and seed).

use std::path::PathBuf;
use std::sync::{Arc, OnceLock};
use std::time::Duration;

use dancegen_generate::models::{Origin, SearchDir, checkout_models};
use dancegen_generate::request::{Character, DancerSelection, OutputRequest, VideoSize};
use dancegen_generate::{CancelToken, Generated, Generator, KeptDance, ModelLocator, Progress};
use pyo3::prelude::*;

use crate::arrays::to_numpy;
use crate::{fail, fail_chain};

/// `generate` options that belong to writing a file: `Dance.save` takes them.
const SAVE_OPTIONS: [&str; 7] = [
    "output",
    "o",
    "progress",
    "rig",
    "character",
    "video-size",
    "follower-only",
];

/// One generator per process: models load once and stay loaded between calls.
fn generator() -> &'static Generator {
    static GENERATOR: OnceLock<Generator> = OnceLock::new();
    GENERATOR.get_or_init(|| Generator::new(locator()))
}

/// The CLI's model search path, then the checkout this package was built from (as a
/// `dancegen` binary built in a checkout finds that checkout's models).
fn locator() -> ModelLocator {
    let mut dirs = ModelLocator::from_environment().search_dirs().to_vec();
    if let Some(dir) = checkout_models()
        && !dirs.iter().any(|d| d.dir == dir)
    {
        dirs.push(SearchDir {
            dir,
            origin: Origin::SourceTree,
        });
    }
    ModelLocator::new(dirs)
}

/// A generated dance.
#[pyclass(module = "dancegen", frozen)]
pub struct Dance {
    done: Generated,
    kept: Arc<KeptDance>,
    joints: OnceLock<(Vec<usize>, Vec<f32>)>,
}

#[pymethods]
impl Dance {
    /// World joint positions, float32, as the CLI's `.npy`: `(T, 24, 3)` metres, Y-up (the
    /// holistic system: `(T, 52, 3)` with the fingers; a group: `(N, T, 24, 3)`; a duet: the
    /// follower).
    #[getter]
    fn joints<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let (shape, data) = match self.joints.get() {
            Some(j) => j.clone(),
            None => {
                let j = py.detach(|| self.kept.joints()).map_err(fail)?;
                self.joints.get_or_init(|| j).clone()
            }
        };
        to_numpy(py, &shape, data)
    }

    /// Frames per second of the motion.
    #[getter]
    fn fps(&self) -> u32 {
        self.done.fps
    }

    /// "solo", "duet", "group" or "holistic".
    #[getter]
    fn system(&self) -> &'static str {
        self.done.system
    }

    /// The model folder used.
    #[getter]
    fn model(&self) -> PathBuf {
        self.done.model_dir.clone()
    }

    /// Seconds of the song danced to: `(start, end)`.
    #[getter]
    fn span(&self) -> (f64, f64) {
        (self.done.start_s, self.done.end_s)
    }

    /// Number of dancers, given ones (a duet's leader) included.
    #[getter]
    fn dancers(&self) -> usize {
        self.done.dancers.len()
    }

    /// Music beats in the danced part, seconds from its start.
    #[getter]
    fn beat_times(&self) -> Vec<f64> {
        self.done.beat_times_s.clone()
    }

    #[getter]
    fn tempo_bpm(&self) -> f64 {
        self.done.tempo_bpm
    }

    /// What was made, as `dancegen generate` prints it.
    #[getter]
    fn summary(&self) -> String {
        self.done.summary.clone()
    }

    /// What the user should know about the result (a song without a beat), as the CLI warns.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.done.warnings.clone()
    }

    /// Post-processing remarks.
    #[getter]
    fn notes(&self) -> Vec<String> {
        self.done.notes.clone()
    }

    /// Writes the dance in the format of `path`'s extension (.glb .fbx .bvh .npz .npy .json
    /// .gif .mp4 .csv): the file `dancegen generate -o PATH` writes with the same options.
    /// `rig`, `character`, `video_size` and `follower_only` are `generate`'s flags. Returns
    /// the paths written (a group's `.bvh` and `.npz` are one file per dancer).
    #[pyo3(signature = (path, rig="smpl", character=None, video_size="640x480", follower_only=false))]
    fn save(
        &self,
        py: Python<'_>,
        path: PathBuf,
        rig: &str,
        character: Option<PathBuf>,
        video_size: &str,
        follower_only: bool,
    ) -> PyResult<Vec<PathBuf>> {
        let rig = dancegen_generate::flags::values::parse_rig(rig).map_err(fail)?;
        let video = VideoSize::parse(video_size).map_err(fail)?;
        if follower_only && self.done.system != "duet" {
            return Err(fail("follower_only writes a duet's follower alone"));
        }
        let dancers = if follower_only {
            DancerSelection::Generated
        } else {
            DancerSelection::Auto
        };
        let character = match character {
            None => None,
            Some(c) => {
                let is_glb = path
                    .extension()
                    .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
                if !is_glb {
                    return Err(fail(format!(
                        "character {}: the character dances in a .glb; save to NAME.glb",
                        c.display()
                    )));
                }
                let several = match self.done.system {
                    "group" => true,
                    "duet" => !follower_only,
                    _ => false,
                };
                if several {
                    return Err(fail(
                        "character puts one dancer on the character: with a leader add \
                         follower_only=True; a group has several dancers",
                    ));
                }
                let loaded = py.detach(|| Character::load(&c)).map_err(fail)?;
                Some(Arc::new(loaded))
            }
        };
        let request = OutputRequest {
            path,
            dancers,
            rig,
            character,
            video,
        };
        py.detach(|| self.kept.write(&[request])).map_err(fail)
    }

    fn __repr__(&self) -> String {
        format!(
            "Dance({}, {} dancer(s), {:.2}-{:.2} s at {} fps: {})",
            self.done.system,
            self.done.dancers.len(),
            self.done.start_s,
            self.done.end_s,
            self.done.fps,
            self.done.summary
        )
    }
}

/// `dancegen generate` with its options by name (`options_json`: a JSON object of long flag
/// names, as a `dancegen batch` manifest line has them, `song` among them); writes nothing.
#[pyfunction]
pub fn generate_named(py: Python<'_>, options_json: &str) -> PyResult<Dance> {
    let fields: serde_json::Map<String, serde_json::Value> =
        serde_json::from_str(options_json).map_err(|e| fail(format!("options: {e}")))?;
    let args = dancegen_generate::flags::args_from_named(
        &fields,
        &SAVE_OPTIONS,
        "is an option of Dance.save (generate writes no file)",
        &|p| Ok(p.to_string()),
    )
    .map_err(fail)?;
    let flags = dancegen_generate::flags::parse(&args).map_err(fail)?;
    let mut request = dancegen_generate::flags::request(&flags).map_err(fail_chain)?;
    // Files are written by Dance.save.
    request.outputs.clear();
    // Ctrl-C stops the job. Python handles signals on its main thread only, and progress is
    // reported from whichever thread samples, so the job runs on a thread of its own while
    // this (the caller's) thread looks for a pending KeyboardInterrupt every 50 ms and cancels
    // the job (it stops within a sampler step).
    let cancel = CancelToken::new();
    let (done, interrupt) = py.detach(|| {
        std::thread::scope(|s| {
            let job = s.spawn(|| generator().run_keeping(&request, &|_: &Progress| {}, &cancel));
            let mut interrupt = None;
            while !job.is_finished() {
                std::thread::sleep(Duration::from_millis(50));
                if interrupt.is_none()
                    && let Err(e) = Python::attach(|py| py.check_signals())
                {
                    cancel.cancel();
                    interrupt = Some(e);
                }
            }
            (job.join(), interrupt)
        })
    });
    if let Some(e) = interrupt {
        return Err(e);
    }
    let done = done.map_err(|_| fail("the generation failed unexpectedly (please report)"))?;
    let done = done.map_err(|e| fail_chain(e.into()))?;
    let kept = done
        .kept
        .clone()
        .ok_or_else(|| fail("the generator kept no dance (please report)"))?;
    Ok(Dance {
        done,
        kept,
        joints: OnceLock::new(),
    })
}
