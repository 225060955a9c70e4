//! `dancegen generate`'s options, named once for every front end that takes them by name: the
//! CLI's flags, `dancegen batch`'s manifest keys and the Python package's keyword arguments
//! all become [`GenerateFlags`] (parsed by clap from an argument list, [`parse`]) and then a
//! [`Request`](crate::Request) ([`request`]), so that each front end accepts the same names,
//! checks them the same way and refuses them in the same words.

mod request;
pub mod values;

use std::path::PathBuf;

use clap::{Args, CommandFactory, FromArgMatches, ValueEnum};
use dancegen_formats::rig::Rig;
use serde_json::{Map, Value};

use crate::request::VideoSize;
pub use request::request;
use values::{parse_range, parse_rig, parse_source_fps};

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum SamplerFlag {
    /// Lodge++: choreography network → primitives → all windows in parallel.
    Lodgepp,
    /// EDGE's long-form sampling (half-overlapping windows, no primitives), for comparison.
    Edge,
    /// Window after window, continuing the previous window (solo: no choreography network;
    /// duet: the ablation of Blocked Local Context).
    Autoregressive,
    /// Duet: Blocked Local Context, every block of the follower at once (ReactDance).
    Blc,
    /// Group: long group diffusion sampling, window after window (TCDiff++ LGDS, window 0
    /// kept).
    Lgds,
    /// Group: every window at once with EDGE's first-half overwrite and stitching.
    Parallel,
}

#[derive(Args, Debug)]
pub struct GenerateFlags {
    /// Song (WAV, FLAC, OGG, MP3, ...); default: the bundled demo song.
    pub song: Option<PathBuf>,
    /// The dance system (default: solo, or duet with --leader).
    #[arg(long, value_parser = clap::builder::PossibleValuesParser::new(
        crate::systems::SYSTEMS.map(|s| s.name)))]
    pub system: Option<String>,
    /// Output file, by extension: .glb .fbx .bvh .npz (SMPL) .npy (joints (T, 24, 3), metres,
    /// Y-up, 30 fps) .json .gif .mp4 (preview with the song) .csv (the face as Live Link Face
    /// ARKit weights; --system holistic only, whose .glb .fbx .bvh .npz .npy .json also hold
    /// the fingers: 52 SMPL-H joints). Repeatable. Default: dance.glb.
    #[arg(short, long, value_name = "FILE")]
    pub output: Vec<PathBuf>,
    /// Bone names of .bvh, .fbx and .glb: smpl, mixamo (mixamorig:Hips, ...), ue5 (pelvis,
    /// thigh_l, ...) or vrm (hips, leftUpperLeg, ...). The joints stand in the same places in
    /// every rig; .npy, .npz and .json keep SMPL's names and order.
    #[arg(long, default_value = "smpl", value_parser = parse_rig)]
    pub rig: Rig,
    /// Picture size of an .mp4 output: 640x480, or 1280x720 (sharper, about three times the
    /// rendering time).
    #[arg(long, value_name = "WxH", default_value = "640x480", value_parser = VideoSize::parse)]
    pub video_size: VideoSize,
    /// Your own humanoid character (.glb, .vrm or .gltf with a skinned mesh): the .glb outputs
    /// become it dancing, retargeted onto its bones (matched by name — Mixamo, UE, VRM, SMPL,
    /// Blender-style — and hierarchy), its rest pose and its height. One dancer (with a leader,
    /// add --follower-only).
    #[arg(long, value_name = "CHARACTER.glb")]
    pub character: Option<PathBuf>,
    /// Model directory (default: lodgepp-small, or reactdance-small with --leader, found on
    /// the model search path: `dancegen models` shows it).
    #[arg(long, value_name = "DIR")]
    pub model: Option<PathBuf>,
    /// Edit this dance: keep it, except the --regenerate ranges, which are made new to join
    /// it (or continue it: --extend). A .npz that dancegen wrote records its song, --start, system, model and seed, and
    /// they are used unless given; any other motion `convert` reads needs SONG (and --start
    /// if it does not dance from the song's start). See "Edits" below for the systems.
    #[arg(long, value_name = "DANCE")]
    pub edit: Option<PathBuf>,
    /// With --edit: keep the whole dance and dance on to --end (the song's end by default),
    /// e.g. a 30 s dance continued to a minute.
    #[arg(long, requires = "edit")]
    pub extend: bool,
    /// With --edit: seconds A-B of the dance to make new, e.g. 8-12 (repeatable; at least
    /// 0.5 s each, inside the dance, not overlapping).
    #[arg(long, value_name = "A-B", requires = "edit", value_parser = parse_range)]
    pub regenerate: Vec<[f64; 2]>,
    /// Start the dance with this motion's last second, unchanged (any format `convert`
    /// reads; one dancer), and continue from there on the song from --start.
    #[arg(long, value_name = "MOTION", conflicts_with = "edit")]
    pub continue_from: Option<PathBuf>,
    /// Keep these joints' rotations from --from for the whole dance and make the rest to go
    /// with them and the music: upper, lower (legs, pelvis and root path), arms, legs, or SMPL
    /// joint names separated by commas (left_knee,right_knee). Without --end the dance lasts
    /// as long as the --from motion.
    #[arg(long, value_name = "SET", requires = "from")]
    pub keep_joints: Option<String>,
    /// The motion --keep-joints keeps joints of (any format `convert` reads; one dancer).
    #[arg(long, value_name = "MOTION", requires = "keep_joints")]
    pub from: Option<PathBuf>,
    /// The rate --from was captured at, whatever its file's header says (e.g. 60 for the CMU
    /// salsa BVHs, whose headers say 120).
    #[arg(long, value_name = "FPS", requires = "from", value_parser = parse_source_fps)]
    pub from_fps: Option<f64>,
    /// Reach a pose at a time: POSE@T, where POSE is a motion file `convert` reads (its first
    /// frame, or frame N with POSE:N) and T is seconds of the song (repeatable). Its joints
    /// are matched in world space on that frame; the dance eases in and out of it. The dancer
    /// stays where it is on the floor unless --keyframe-root.
    #[arg(long, value_name = "POSE@T")]
    pub keyframe: Vec<String>,
    /// The joints the keyframes place (as --keep-joints names them; default all). Each
    /// named joint's chain from the pelvis takes the pose's rotations, so that the joint is
    /// where the pose has it around the pelvis. With both legs named, the pelvis takes the
    /// pose's height too; without them it keeps the dance's height, so that the dance's own
    /// legs still stand on the floor.
    #[arg(long, value_name = "SET", requires = "keyframe")]
    pub keyframe_joints: Option<String>,
    /// The keyframes' floor position is reached too (the pose file's pelvis x, z).
    #[arg(long, requires = "keyframe")]
    pub keyframe_root: bool,
    /// The dancer's root follows keyframed floor positions: a FORMATION.json of one dancer
    /// ({"keyframes": [{"t": 0, "positions": [[x, z]]}, ...]}, seconds of the song, metres,
    /// x to the audience's right, +z towards the audience).
    #[arg(long, value_name = "PATH.json")]
    pub path: Option<PathBuf>,
    /// Duet: the leader's motion (any format `convert` reads; BVH is retargeted to SMPL 24).
    /// It needs joint rotations: a solo dance for it is a `generate -o leader.npz` (or .bvh),
    /// not the joint positions of `.npy`.
    /// The follower gets the leader's length at 30 fps, in the leader's world frame; outputs
    /// hold both dancers (leader unchanged), except single-dancer formats (.bvh, .npz, .npy)
    /// which hold the follower.
    #[arg(long, value_name = "FILE")]
    pub leader: Option<PathBuf>,
    /// Duet: the rate the leader was captured at, whatever its file's header says (the frames
    /// stay the same, their times change), e.g. 60 for the CMU salsa BVHs whose headers say
    /// 120. Needed for a file whose header has no rate.
    #[arg(long, value_name = "FPS", requires = "leader", value_parser = parse_source_fps)]
    pub leader_fps: Option<f64>,
    /// Duet: write the follower alone to every output.
    #[arg(long, requires = "leader")]
    pub follower_only: bool,
    /// Duet and group: keep the dancers exactly where the model put them, even where one
    /// body passes through another (by default a smooth horizontal shift moves them apart;
    /// hands may touch).
    #[arg(long)]
    pub no_separation: bool,
    /// Group: number of dancers (2-5). `.npy` then holds `(N, T, 24, 3)`, `.bvh` and `.npz`
    /// are written once per dancer (`name_0.bvh`, ...), `.json` adds every root trajectory and
    /// the left-to-right order at the start and at the end.
    #[arg(long, value_name = "N")]
    pub dancers: Option<usize>,
    /// Group: where each dancer should be and when: {"keyframes": [{"t": seconds, "positions":
    /// [[x, z] or null, ... one per dancer]}, ...]}, metres, x to the audience's right, +z
    /// towards the audience; minimum-jerk paths between keyframes. Default: the model chooses.
    #[arg(long, value_name = "FORMATION.json")]
    pub formation: Option<PathBuf>,
    /// Group: every dancer dances the same moves (the leftmost dancer's), each on its own path.
    #[arg(long)]
    pub unison: bool,
    /// Holistic: a (52, 103) ARKit -> FLAME matrix (.npy, yours: FLAME and SoulNet's mapping
    /// are not redistributable); the .json then also holds the face as FLAME's 100 expression
    /// and 3 jaw values per frame ("flame").
    #[arg(long, value_name = "MAPPING.npy")]
    pub flame_mapping: Option<PathBuf>,
    /// Duet: guidance s of the coarse (base) HFSQ level, x̂0 = (1 + s)·cond − s·uncond
    /// (default: the model's).
    #[arg(long, requires = "leader")]
    pub guidance_coarse: Option<f64>,
    /// Duet: guidance s of the fine (residual) levels (default: the model's).
    #[arg(long, requires = "leader")]
    pub guidance_fine: Option<f64>,
    /// Duet: guidance s per level, coarse first (the last value repeats), e.g. 1.5,0.5,0.5.
    #[arg(long, requires = "leader", value_delimiter = ',', num_args = 1..,
        conflicts_with_all = ["guidance_coarse", "guidance_fine"])]
    pub guidance_levels: Vec<f64>,
    /// Dance genre (the model's list; default: the model's default genre).
    #[arg(long)]
    pub genre: Option<String>,
    /// Random seed (default: 0, or the recorded seed of the --edit dance).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Denoising steps (default: the model's, 50).
    #[arg(long)]
    pub steps: Option<usize>,
    /// Classifier-free guidance weight w (default: the model's, 2). Duet: one weight for every
    /// level (single-scale CFG, s = w − 1) instead of the layer-wise guidance.
    #[arg(long)]
    pub guidance: Option<f64>,
    /// Start of the music to dance to (seconds; with --edit: the recorded start).
    #[arg(long)]
    pub start: Option<f64>,
    /// End of the music to dance to (seconds; default: the song's end).
    #[arg(long)]
    pub end: Option<f64>,
    /// Long-form sampler (default: lodgepp solo, blc duet).
    #[arg(long, value_enum)]
    pub sampler: Option<SamplerFlag>,
    /// Switch off the Foot Refine Block (ablation).
    #[arg(long)]
    pub no_foot_refine: bool,
    /// Switch off the penetration guidance (ablation).
    #[arg(long)]
    pub no_penetration_guidance: bool,
    /// Leave the feet as generated: no root-path correction for the support foot and no leg IK
    /// pinning planted feet (post-processing steps, not part of Lodge++, ReactDance, TCDiff++
    /// or SoulNet; a duet follower gets the root correction only, on a leash to its leader).
    #[arg(long)]
    pub no_foot_lock: bool,
    /// Leave the timing as generated: no time warp moving the dance's beats onto the song's
    /// (solo, each group dancer, a group edit's new parts with the kept frames around them
    /// fixed) or the follower's onto the leader's (duet); post-processing,
    /// not part of Lodge++, ReactDance or TCDiff++; the playback speed stays within ±15 %.
    #[arg(long)]
    pub no_beat_align: bool,
}

/// `generate`'s options alone, for clap.
#[derive(clap::Parser, Debug)]
#[command(name = "generate", no_binary_name = true)]
struct GenerateCommand {
    #[command(flatten)]
    flags: GenerateFlags,
}

/// Parses an argument list (without the program and command names) as `dancegen generate`
/// would; the error is clap's message on one line.
pub fn parse(args: &[String]) -> Result<GenerateFlags, String> {
    let matches = GenerateCommand::command()
        .try_get_matches_from(args)
        .map_err(|e| clap_message(&e.to_string()))?;
    GenerateCommand::from_arg_matches(&matches)
        .map(|c| c.flags)
        .map_err(|e| clap_message(&e.to_string()))
}

/// clap's message on one line, without its usage and help hints.
fn clap_message(s: &str) -> String {
    s.lines()
        .take_while(|l| !l.trim().is_empty() && !l.starts_with("Usage:"))
        .map(|l| l.trim().trim_start_matches("error: "))
        .collect::<Vec<_>>()
        .join(" ")
}

/// Options whose values are paths (as named in [`args_from_named`], kebab-case).
pub const PATH_OPTIONS: [&str; 9] = [
    "song",
    "leader",
    "formation",
    "model",
    "character",
    "edit",
    "continue-from",
    "from",
    "path",
];

/// `generate`'s argument list for options given by name (`fields`: long names in `snake_case`
/// or `kebab-case`; `true`/`false` for switches, a list for a repeatable option, `null` for
/// none), the song last after `--`. A name in `reserved` is refused with `why_reserved`;
/// `resolve` turns each path value (see [`PATH_OPTIONS`]) into the path to pass.
pub fn args_from_named(
    fields: &Map<String, Value>,
    reserved: &[&str],
    why_reserved: &str,
    resolve: &dyn Fn(&str) -> Result<String, String>,
) -> Result<Vec<String>, String> {
    let command = GenerateCommand::command();
    let mut args = Vec::new();
    let mut song = None;
    for (key, value) in fields {
        let name = key.replace('_', "-");
        if reserved.contains(&name.as_str()) {
            return Err(format!("\"{key}\" {why_reserved}"));
        }
        if name == "song" {
            match value {
                Value::String(s) => song = Some(resolve(s)?),
                Value::Null => {}
                other => return Err(format!("\"song\" must be a path, not {other}")),
            }
            continue;
        }
        let Some(arg) = command
            .get_arguments()
            .find(|a| a.get_long() == Some(name.as_str()))
        else {
            return Err(format!(
                "unknown option \"{key}\" (`dancegen generate` has no --{name})"
            ));
        };
        let takes_value = arg.get_action().takes_values();
        let is_path = PATH_OPTIONS.contains(&name.as_str());
        let values: Vec<&Value> = match value {
            Value::Array(items) if takes_value => items.iter().collect(),
            Value::Null => continue,
            v => vec![v],
        };
        for v in values {
            let text = match (v, takes_value) {
                (Value::Bool(true), false) => {
                    args.push(format!("--{name}"));
                    continue;
                }
                (Value::Bool(false), false) => continue,
                (_, false) => return Err(format!("\"{key}\" is a switch: give true or false")),
                (Value::String(s), true) if is_path => resolve(s)?,
                // POSE[:N]@T: the pose file is a path.
                (Value::String(s), true) if name == "keyframe" => {
                    let (pose, frame, t) = crate::edit::parse_keyframe_spec(s)?;
                    let pose = resolve(&pose.display().to_string())?;
                    format!("{pose}:{frame}@{t}")
                }
                (Value::String(s), true) => s.clone(),
                (Value::Number(n), true) => n.to_string(),
                (other, true) => return Err(format!("\"{key}\": {other} is not a value")),
            };
            // `--name=value`, so a value starting with '-' is not read as an option.
            args.push(format!("--{name}={text}"));
        }
    }
    if let Some(song) = song {
        args.push("--".into());
        args.push(song);
    }
    Ok(args)
}
