//! Holistic: one dancer with fingers and a face (SoulNet, `dancegen_soulnet`).
//!
//! Song span → EDGE-35 features → part tokens window by window → `[body | hands | face]` frames
//! → SMPL-H 52 motion standing on the floor (its first 22 joints are also the SMPL 24 body every
//! other output and the previews use) and 52 ARKit weights per frame.

use std::path::Path;

use dancegen_lodgepp::planted_feet::{clean_planted_feet, lock_planted_feet};
use dancegen_motion::face::{FaceWeights, flame::FlameMapping};
use dancegen_motion::repr::{Edge151, SmplMotion};
use dancegen_motion::skeleton::Skeleton;
use dancegen_nn::burn::tensor::Device;
use dancegen_soulnet::bundle::HolisticModel;
use dancegen_soulnet::pipeline::{self, GenerateOptions, TOKENS};

use crate::edit;
use crate::error::GenerateError;
use crate::song::FPS;
use crate::system::CommonOptions;
use crate::system::{Dance, DanceInput, DanceSystem, Dancer, HolisticParts, Role};
use crate::systems::solo::keep_feet_above_floor;

pub use super::holistic_options::{HolisticOptions, MIN_SONG_SECONDS};

pub struct Holistic;

impl DanceSystem for Holistic {
    const NAME: &'static str = "holistic";
    const MODEL_KIND: &'static str = dancegen_soulnet::bundle::KIND;
    const DEFAULT_MODEL: &'static str = "soulnet-small";
    const PARTS: &'static [(&'static str, f64)] = &[(TOKENS, 1.0)];
    const EDITS: &'static [&'static str] = &edit::OPERATIONS;
    const MIN_SECONDS: f64 = super::holistic_options::MIN_SONG_SECONDS;
    const SECONDS_PER_DANCED_SECOND: f64 = 0.2;

    type Model = HolisticModel;
    type Options = HolisticOptions;

    fn load(dir: &Path, device: &Device) -> Result<HolisticModel, GenerateError> {
        HolisticModel::load(dir, device).map_err(|e| GenerateError::ModelLoad {
            system: "SoulNet",
            dir: dir.to_path_buf(),
            source: Box::new(e),
        })
    }

    fn check(
        _: &HolisticModel,
        common: &CommonOptions,
        options: &HolisticOptions,
    ) -> Result<(), GenerateError> {
        common.check_sampling("4 = SoulNet's")?;
        if let Some(g) = &common.genre {
            return Err(GenerateError::Invalid(format!(
                "--genre {g}: the holistic model has no genres (it dances to the music alone)"
            )));
        }
        if let Some(p) = &options.flame_mapping {
            FlameMapping::read(p).map_err(|e| GenerateError::Invalid(e.to_string()))?;
        }
        Ok(())
    }

    fn dance(
        model: &HolisticModel,
        input: DanceInput<'_, HolisticOptions>,
    ) -> Result<Dance, GenerateError> {
        if !input.common.edit.is_empty() {
            return super::holistic_edit::edit(model, &input);
        }
        let song = input.song;
        let span = song.span(input.common.start, input.common.end)?;
        if span.seconds() < MIN_SONG_SECONDS {
            return Err(GenerateError::Invalid(format!(
                "{}: {:.2} s of music to dance to; the model needs at least {MIN_SONG_SECONDS} s",
                song.label,
                span.seconds()
            )));
        }
        let mut opts = GenerateOptions::defaults(model, input.common.seed);
        if let Some(s) = input.common.steps {
            opts.sampling.steps = s;
        }
        if let Some(w) = input.common.guidance {
            opts.sampling.cond_scale = w;
        }
        let made = pipeline::generate(model, song.music(&span), &opts, input.device, input.hook)
            .map_err(|e| match e {
                pipeline::GenerateError::Cancelled(_) => GenerateError::Cancelled,
                pipeline::GenerateError::Invalid(r) => GenerateError::Generation(r),
            })?;
        let decoded = dancegen_soulnet::layout::decode(&made.rows, FPS as f32)
            .map_err(GenerateError::Generation)?;
        let mut hol = decoded.motion;
        let t = hol.frames();
        let mut body = SmplMotion {
            fps: FPS as f32,
            poses: body_of(&hol.poses, t),
            trans: hol.trans.clone(),
        };
        let gen_err = |e: &dyn std::fmt::Display| GenerateError::Generation(e.to_string());
        let mut notes = vec![
            "the fingers and face were learned from synthetic data (see the model card)".into(),
        ];
        if input.options.foot_lock {
            // Through EDGE-151 frames (their contact channel: EDGE's velocity labels), as the
            // group system does; only the body's joints and root change.
            let mut frames = Edge151::encode(&body).map_err(|e| gen_err(&e))?;
            if model.config.sampling.foot_ik {
                clean_planted_feet(&mut frames);
            } else {
                lock_planted_feet(&mut frames);
            }
            body = Edge151::decode(&frames).map_err(|e| gen_err(&e))?;
            for f in 0..t {
                hol.poses[f * 156..f * 156 + 66].copy_from_slice(&body.poses[f * 72..f * 72 + 66]);
            }
            notes.push(if model.config.sampling.foot_ik {
                "planted feet locked: root lock and leg IK (post-processing, not part of SoulNet)"
                    .into()
            } else {
                "planted feet locked: root lock (post-processing, not part of SoulNet)".into()
            });
        }
        // The planted feet on the floor frame by frame, as for the solo (systems::solo::to_smpl).
        body.put_feet_on_tracked_floor().map_err(|e| gen_err(&e))?;
        keep_feet_above_floor(&mut body).map_err(GenerateError::Generation)?;
        hol.trans.clone_from(&body.trans);
        let face_values = decoded.face[..t * dancegen_motion::face::ARKIT_COUNT].to_vec();
        let face = FaceWeights::new(face_values, FPS as f32).map_err(|e| gen_err(&e))?;
        let flame = match &input.options.flame_mapping {
            Some(p) => {
                let m = FlameMapping::read(p).map_err(|e| GenerateError::Invalid(e.to_string()))?;
                Some((0..t).flat_map(|f| m.to_flame(face.frame(f))).collect())
            }
            None => None,
        };
        Ok(Dance {
            dancers: vec![Dancer {
                role: Role::Solo,
                motion: body,
            }],
            span,
            summary: format!(
                "{t} frames ({:.1} s at {FPS} fps) with fingers and face, seed {}, {} window{}",
                t as f64 / f64::from(FPS),
                input.common.seed,
                made.windows,
                if made.windows == 1 { "" } else { "s" },
            ),
            timing_breakdown: String::new(),
            notes,
            group: None,
            holistic: Some(HolisticParts {
                poses: hol.poses,
                trans: hol.trans,
                skeleton: Skeleton::smplh52_approx(),
                face,
                flame,
            }),
        })
    }
}

/// SMPL 24 rotations of SMPL-H 52 ones: body joints 0–21, the two SMPL hand joints at rest.
fn body_of(poses52: &[f32], t: usize) -> Vec<f32> {
    let mut out = vec![0f32; t * 72];
    for f in 0..t {
        out[f * 72..f * 72 + 66].copy_from_slice(&poses52[f * 156..f * 156 + 66]);
    }
    out
}
