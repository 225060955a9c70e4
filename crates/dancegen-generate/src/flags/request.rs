//! The [`Request`] that [`GenerateFlags`] describe: the system chosen from `--system`,
//! `--leader` and the edited dance's record, each system's options, the edits and the outputs.

use std::path::PathBuf;

use anyhow::{Result, bail};

use super::{GenerateFlags, SamplerFlag};
use crate::edit::{Edit, GivenMotion, KeepJoints, KeyframePose, dance_file, parse_joint_set};
use crate::formation_file::FormationFile;
use crate::record::DanceRecord;
use crate::request::{Character, CommonOptions, DancerSelection, OutputRequest};
use crate::systems::duet::{DuetOptions, DuetSampler, load_leader_at};
use crate::systems::group::{GroupOptions, LongSampler};
use crate::systems::holistic::HolisticOptions;
use crate::systems::solo::{SoloOptions, SoloSampler};
use crate::{Request, Song, SystemRequest, systems};

/// The library request the flags describe (also each line of `dancegen batch`).
pub fn request(args: &GenerateFlags) -> Result<Request> {
    let edited = edited_dance(args)?;
    let edit_name = args
        .edit
        .as_ref()
        .map(|p| p.display().to_string())
        .unwrap_or_default();
    let recorded = edited.as_ref().and_then(|e| e.record.as_ref());
    let continue_from = match &args.continue_from {
        Some(p) => Some(GivenMotion::load_dance(
            p,
            "the motion to continue",
            None,
            "convert it first: dancegen convert FILE --source-fps N -o motion.npz",
        )?),
        None => None,
    };
    // A group given to edit or to continue makes a group dance of as many dancers.
    let given_group = edited
        .as_ref()
        .map(|e| &e.dance)
        .into_iter()
        .chain(continue_from.as_ref())
        .map(GivenMotion::dancers)
        .find(|&n| n > 1);
    let system = match (args.system.as_deref(), &args.leader, recorded) {
        (Some(s), _, Some(r)) if s != r.system => bail!(
            "--edit {}: a {} dance; it is edited with --system {} (or without --system)",
            edit_name,
            r.system,
            r.system
        ),
        (None, None, Some(r)) => r.system.as_str(),
        (None, None, None) if given_group.is_some() => "group",
        (None, None, None) => "solo",
        (None, Some(_), _) => "duet",
        (Some(s), _, _) => s,
    };
    let info = systems::by_name(system).map_err(anyhow::Error::msg)?;
    let system = match (info.name, &args.leader) {
        ("solo", Some(_)) => {
            bail!("--leader makes a duet; use --system duet (or leave --system out)")
        }
        ("solo", None) => SystemRequest::Solo(solo_options(args)?),
        ("duet", Some(leader)) => SystemRequest::Duet(duet_options(args, leader)?),
        ("duet", None) if recorded.is_some() => bail!(
            "--edit {edit_name}: the follower of a duet; give the leader it dances with, \
             --leader FILE"
        ),
        ("duet", None) => bail!("the duet system dances with a leader: give --leader FILE"),
        ("group", Some(_)) => bail!("--leader makes a duet; the group system takes no leader"),
        ("group", None) => SystemRequest::Group(group_options(args, given_group)?),
        ("holistic", Some(_)) => {
            bail!("--leader makes a duet; the holistic system dances alone")
        }
        ("holistic", None) => SystemRequest::Holistic(HolisticOptions {
            foot_lock: !args.no_foot_lock,
            flame_mapping: args.flame_mapping.clone(),
        }),
        (other, _) => bail!("--system {other} is not wired into this command yet"),
    };
    let group = matches!(system, SystemRequest::Group(_));
    if !group && (args.dancers.is_some() || args.formation.is_some() || args.unison) {
        bail!("--dancers, --formation and --unison make a group dance: add --system group");
    }
    if args.flame_mapping.is_some() && !matches!(system, SystemRequest::Holistic(_)) {
        bail!("--flame-mapping maps a face: add --system holistic");
    }
    let duet = matches!(system, SystemRequest::Duet(_));
    let outputs: Vec<PathBuf> = if args.output.is_empty() {
        vec![PathBuf::from(match (duet, group) {
            (true, _) => "couple.glb",
            (_, true) => "group.glb",
            _ => "dance.glb",
        })]
    } else {
        args.output.clone()
    };
    let character = match &args.character {
        None => None,
        Some(path) => {
            if !outputs.iter().any(|o| has_extension(o, "glb")) {
                bail!(
                    "--character {}: the character dances in the .glb outputs; add -o NAME.glb",
                    path.display()
                );
            }
            // Checked before any work: a .glb of several dancers cannot be one character.
            if group || (duet && !args.follower_only) {
                bail!(
                    "--character puts one dancer on the character: with a leader add \
                     --follower-only; a group has several dancers"
                );
            }
            Some(std::sync::Arc::new(Character::load(path)?))
        }
    };
    let dancers = if args.follower_only {
        DancerSelection::Generated
    } else {
        DancerSelection::Auto
    };
    let song = match (&args.song, recorded) {
        (Some(p), _) => Song::File(p.clone()),
        (None, Some(r)) => match r.song_path() {
            Some(p) if !p.is_file() => bail!(
                "--edit {}: its song {} is not there any more; give the song file as SONG",
                edit_name,
                p.display()
            ),
            p => Song::file_or_demo(p.as_deref()),
        },
        (None, None) if edited.is_some() => bail!(
            "--edit {}: it has no dancegen record (a foreign dance), so give the SONG it dances \
             to (and --start if it does not start at the song's start)",
            edit_name
        ),
        (None, None) => Song::Demo,
    };
    // A recorded model folder is used when it is still there; otherwise the default one.
    let model = args.model.clone().or_else(|| {
        recorded
            .map(|r| PathBuf::from(&r.model))
            .filter(|d| d.join("model.toml").is_file())
    });
    let keep_joints = match (&args.keep_joints, &args.from) {
        (Some(spec), Some(from)) => {
            let (joints, root) =
                parse_joint_set("--keep-joints", spec).map_err(anyhow::Error::msg)?;
            Some(KeepJoints {
                spec: spec.clone(),
                joints,
                root,
                from: GivenMotion::load_dance(
                    from,
                    "the motion to keep joints from",
                    args.from_fps,
                    "--from-fps N",
                )?,
            })
        }
        _ => None,
    };
    let keyframes = args
        .keyframe
        .iter()
        .map(|spec| KeyframePose::load(spec))
        .collect::<Result<Vec<_>, _>>()?;
    let keyframe_joints = match &args.keyframe_joints {
        Some(spec) => Some((
            spec.clone(),
            parse_joint_set("--keyframe-joints", spec)
                .map_err(anyhow::Error::msg)?
                .0,
        )),
        None => None,
    };
    let path = match &args.path {
        Some(p) => Some(FormationFile::read(p, "the --path")?),
        None => None,
    };
    Ok(Request {
        song,
        system,
        common: CommonOptions {
            seed: args.seed.or(recorded.map(|r| r.seed)).unwrap_or(0),
            steps: args.steps,
            guidance: args.guidance,
            genre: args.genre.clone(),
            start: args.start.or(recorded.map(|r| r.start_s)),
            end: args.end,
            edit: Edit {
                base: edited.map(|e| e.dance),
                regenerate: args.regenerate.clone(),
                extend: args.extend,
                continue_from,
                keep_joints,
                keyframes,
                keyframe_joints,
                keyframe_root: args.keyframe_root,
                path,
            },
        },
        model,
        outputs: outputs
            .into_iter()
            .map(|path| OutputRequest {
                path,
                dancers,
                rig: args.rig,
                character: character.clone(),
                video: args.video_size,
            })
            .collect(),
    })
}

fn has_extension(path: &std::path::Path, ext: &str) -> bool {
    path.extension()
        .is_some_and(|e| e.to_string_lossy().eq_ignore_ascii_case(ext))
}

fn solo_options(args: &GenerateFlags) -> Result<SoloOptions> {
    let sampler = match args.sampler.unwrap_or(SamplerFlag::Lodgepp) {
        SamplerFlag::Lodgepp => SoloSampler::Lodgepp,
        SamplerFlag::Edge => SoloSampler::Edge,
        SamplerFlag::Autoregressive => SoloSampler::Autoregressive,
        SamplerFlag::Blc => bail!("--sampler blc is the duet sampler (use it with --leader)"),
        SamplerFlag::Lgds | SamplerFlag::Parallel => {
            bail!("--sampler lgds/parallel are the group samplers (use them with --system group)")
        }
    };
    if args.no_separation {
        bail!("--no-separation applies to duet and group dances");
    }
    Ok(SoloOptions {
        sampler,
        foot_refine: !args.no_foot_refine,
        penetration_guidance: !args.no_penetration_guidance,
        foot_lock: !args.no_foot_lock,
        beat_align: !args.no_beat_align,
    })
}

/// The group options; `given` is the dancer count of a group given to edit or continue,
/// which `--dancers` defaults to.
fn group_options(args: &GenerateFlags, given: Option<usize>) -> Result<GroupOptions> {
    let Some(n) = args.dancers.or(given) else {
        bail!("--system group needs --dancers N (2 to 5)");
    };
    let sampler = match args.sampler {
        None => None,
        Some(SamplerFlag::Lgds) => Some(LongSampler::Lgds),
        Some(SamplerFlag::Parallel) => Some(LongSampler::Parallel),
        Some(other) => bail!("--sampler {other:?}: the group system samples with lgds or parallel"),
    };
    let mut o = GroupOptions {
        sampler,
        unison: args.unison,
        separation: !args.no_separation,
        foot_lock: !args.no_foot_lock,
        beat_align: !args.no_beat_align,
        ..GroupOptions::new(n)
    };
    if let Some(f) = &args.formation {
        o = o.with_formation_file(f)?;
    }
    Ok(o)
}

/// The `--edit` dance and its record (`None` for a foreign dance).
struct EditedDance {
    dance: GivenMotion,
    record: Option<DanceRecord>,
}

fn edited_dance(args: &GenerateFlags) -> Result<Option<EditedDance>> {
    let Some(path) = &args.edit else {
        return Ok(None);
    };
    let path = &dance_file(path);
    let record = DanceRecord::read(path)?;
    // A duet's .npz holds its follower (dancer 1), which is what a duet edit makes anew; its
    // leader comes with --leader.
    let duet_follower = |r: &DanceRecord| r.system == "duet" && r.dancers == 2 && r.dancer == 1;
    if let Some(r) = &record
        && r.dancers > 1
        && !duet_follower(r)
        && r.system != "group"
    {
        bail!(
            "--edit {}: dancer {} of a {}-dancer {} dance; editing one dancer of several is not \
             supported yet",
            path.display(),
            r.dancer,
            r.dancers,
            r.system
        );
    }
    let dance = GivenMotion::load_dance(
        path,
        "the dance to edit",
        None,
        "convert it first: dancegen convert FILE --source-fps N -o dance.npz",
    )?;
    Ok(Some(EditedDance { dance, record }))
}

fn duet_options(args: &GenerateFlags, leader: &std::path::Path) -> Result<DuetOptions> {
    let sampler = match args.sampler.unwrap_or(SamplerFlag::Blc) {
        SamplerFlag::Blc => DuetSampler::Blc,
        SamplerFlag::Autoregressive => DuetSampler::Autoregressive,
        other => {
            bail!("--sampler {other:?} is a solo sampler; with --leader use blc or autoregressive")
        }
    };
    let motion = load_leader_at(leader, args.leader_fps)?;
    Ok(DuetOptions {
        sampler,
        guidance_coarse: args.guidance_coarse,
        guidance_fine: args.guidance_fine,
        guidance_levels: args.guidance_levels.clone(),
        separation: !args.no_separation,
        foot_lock: !args.no_foot_lock,
        beat_align: !args.no_beat_align,
        ..DuetOptions::new(motion, leader.display().to_string())
    })
}
