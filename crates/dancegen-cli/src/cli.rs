//! Command-line interface definition.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};
use dancegen_formats::rig::Rig;

#[derive(Parser, Debug)]
#[command(name = "dancegen", version, about = "Turn music into 3D dance", long_about = None)]
pub struct Cli {
    /// More log output (-v info, -vv debug, -vvv trace).
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    pub verbose: u8,
    /// Only print errors; no progress bars.
    #[arg(short, long, global = true)]
    pub quiet: bool,
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Per-frame music features the dance models are conditioned on (librosa-compatible).
    Features(FeaturesArgs),
    /// Tempo and beat times of a song, optionally plotted.
    Beats(BeatsArgs),
    /// Convert motion between research formats and the formats animators use.
    Convert(ConvertArgs),
    /// Render a preview of one or more dancers: PNG (one frame), GIF or MP4 (with audio).
    Render(RenderArgs),
    /// Dance metrics (FID, diversity, BAS, PFC, foot skating, MPJPE, ...) under a paper's protocol.
    Eval(EvalArgs),
    /// Train a model from a TOML config (see examples/train/), or continue a run.
    Train(TrainArgs),
    /// Build training sets: motion + music pairs (beat-warp pseudo-pairing, AIST++, FineDance).
    #[command(subcommand)]
    Dataset(DatasetCommand),
    /// Generate a solo dance for a song (Lodge++), or with --leader the partner of a given
    /// leader (ReactDance); the installed default models (see `dancegen models`).
    Generate(GenerateArgs),
    /// Generate many songs from a manifest (one JSON object per line: id, song, outputs and
    /// any `generate` option by name): one model load, resumable (songs with a done.json are
    /// skipped), shardable (--shard I/N) across processes and machines.
    Batch(BatchArgs),
    /// List the models found and where they were looked for, or install models.
    Models(ModelsArgs),
    /// Assemble a model directory from its finished training runs (solo: --vqvae --gpt --pddm;
    /// duet: --hfsq --ldm; group: --group; holistic: --holistic-vq --holistic-mmr
    /// --holistic-generator).
    Bundle(BundleArgs),
    /// The web app: upload a song, follow the progress, watch the dance in 3D in time with
    /// the music, download it (http://127.0.0.1:8080 by default).
    Serve(ServeArgs),
}

#[derive(Args, Debug)]
pub struct ServeArgs {
    /// Address to listen on. Loopback by default: to offer it to others, put a reverse proxy
    /// with TLS and authentication in front (see the README), or give 0.0.0.0:PORT knowingly.
    #[arg(long, default_value = "127.0.0.1:8080")]
    pub addr: std::net::SocketAddr,
    /// Folder for the job database and the jobs' files (default: the platform's data folder,
    /// e.g. ~/.local/share/dancegen/serve).
    #[arg(long, value_name = "DIR")]
    pub data_dir: Option<PathBuf>,
    /// Jobs generated at once (each already uses every core).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=64))]
    pub workers: u16,
    /// Longest song accepted, seconds.
    #[arg(long, default_value_t = 600.0, value_name = "SECONDS")]
    pub max_song_seconds: f64,
    /// Largest upload, MB.
    #[arg(long, default_value_t = 64, value_name = "MB")]
    pub max_upload_mb: usize,
    /// Jobs waiting or running before new ones are refused (HTTP 429).
    #[arg(long, default_value_t = 100, value_name = "N")]
    pub max_queue: usize,
    /// A model folder to serve instead of the installed default (`--model DIR`, repeatable;
    /// its system comes from its model.toml).
    #[arg(long = "model", value_name = "DIR")]
    pub models: Vec<PathBuf>,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum SamplerArg {
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

/// How `generate` reports progress on stderr.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ProgressArg {
    /// A progress bar when stderr is a terminal (nothing with -q).
    #[default]
    Bar,
    /// One JSON object per line: {"stage": ..., "fraction": 0..1, "eta_s": ...}; the last
    /// one has fraction 1.
    Json,
    /// Nothing.
    None,
}

#[derive(Args, Debug)]
pub struct GenerateArgs {
    /// Song (WAV, FLAC, OGG, MP3, ...); default: the bundled demo song.
    pub song: Option<PathBuf>,
    /// The dance system (default: solo, or duet with --leader).
    #[arg(long, value_parser = clap::builder::PossibleValuesParser::new(
        dancegen_generate::systems::SYSTEMS.map(|s| s.name)))]
    pub system: Option<String>,
    /// Progress on stderr.
    #[arg(long, value_enum, default_value_t = ProgressArg::Bar)]
    pub progress: ProgressArg,
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
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Denoising steps (default: the model's, 50).
    #[arg(long)]
    pub steps: Option<usize>,
    /// Classifier-free guidance weight w (default: the model's, 2). Duet: one weight for every
    /// level (single-scale CFG, s = w − 1) instead of the layer-wise guidance.
    #[arg(long)]
    pub guidance: Option<f64>,
    /// Start of the music to dance to (seconds).
    #[arg(long)]
    pub start: Option<f64>,
    /// End of the music to dance to (seconds; default: the song's end).
    #[arg(long)]
    pub end: Option<f64>,
    /// Long-form sampler (default: lodgepp solo, blc duet).
    #[arg(long, value_enum)]
    pub sampler: Option<SamplerArg>,
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
    /// (solo) or the follower's onto the leader's (duet); post-processing, not part of Lodge++
    /// or ReactDance; the playback speed stays within ±15 %.
    #[arg(long)]
    pub no_beat_align: bool,
}

#[derive(Args, Debug)]
pub struct BatchArgs {
    /// The manifest: one JSON object per line, e.g. {"id": "song-1", "song": "songs/a.mp3",
    /// "system": "solo", "seed": 7, "outputs": ["dance.glb", "dance.npy"], "genre": "salsa"}.
    /// Keys are `generate`'s options (snake_case or kebab-case; true for a switch); the seed
    /// defaults to a hash of the id; relative paths are taken from the manifest's folder (or
    /// the current one).
    pub manifest: PathBuf,
    /// Output folder: DIR/<id>/<output>, DIR/<id>/done.json once a song is complete, and one
    /// line per song in DIR/results.jsonl ({"id", "line", "error", "skipped", "seconds"}).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Take only the lines whose 0-based index mod N is I (e.g. a Kubernetes Indexed Job's
    /// $JOB_COMPLETION_INDEX/N or a Slurm array's $SLURM_ARRAY_TASK_ID/N).
    #[arg(long, value_name = "I/N")]
    pub shard: Option<crate::batch::Shard>,
    /// Songs generated at once in this process (each already uses every core; more helps
    /// only to overlap song decoding and file writing).
    #[arg(long, default_value_t = 1, value_name = "K",
        value_parser = clap::value_parser!(u16).range(1..=64))]
    pub jobs: u16,
}

#[derive(Args, Debug)]
pub struct ModelsArgs {
    #[command(subcommand)]
    pub command: Option<ModelsCommand>,
    /// Print the list as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Subcommand, Debug)]
pub enum ModelsCommand {
    /// The models found on the search path, and the folders searched (the default).
    List {
        /// Print the list as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Copy models (folders holding model.toml) into the data folder, where every dancegen
    /// binary of this user finds them.
    Install {
        /// A folder of models or one model folder (default: the models/ folder of the
        /// checkout this binary was built from).
        #[arg(long, value_name = "DIR")]
        from: Option<PathBuf>,
        /// Destination folder of models (default: the platform data folder).
        #[arg(long, value_name = "DIR")]
        to: Option<PathBuf>,
    },
}

#[derive(Args, Debug)]
pub struct BundleArgs {
    /// Finished `lodgepp_vqvae` run directory (solo model).
    #[arg(long, value_name = "RUN", requires_all = ["gpt", "pddm"], conflicts_with_all = ["hfsq", "ldm"])]
    pub vqvae: Option<PathBuf>,
    /// Finished `lodgepp_gpt` run directory (solo model).
    #[arg(long, value_name = "RUN", requires = "vqvae")]
    pub gpt: Option<PathBuf>,
    /// Finished `lodgepp_pddm` run directory (solo model).
    #[arg(long, value_name = "RUN", requires = "vqvae")]
    pub pddm: Option<PathBuf>,
    /// Finished `reactdance_hfsq` run directory (duet model).
    #[arg(long, value_name = "RUN", requires = "ldm")]
    pub hfsq: Option<PathBuf>,
    /// Finished `reactdance_ldm` run directory (duet model), or a duet model directory: its
    /// latent model, normaliser and sampling settings are kept, its autoencoder replaced.
    #[arg(long, value_name = "RUN", requires = "hfsq")]
    pub ldm: Option<PathBuf>,
    /// Finished `tcdiffpp_group` run directory (group model).
    #[arg(long, value_name = "RUN", conflicts_with_all = ["vqvae", "hfsq"])]
    pub group: Option<PathBuf>,
    /// Finished `soulnet_vq` run directory (holistic model; with --holistic-mmr and
    /// --holistic-generator, or with --holistic-model).
    #[arg(long, value_name = "RUN", conflicts_with_all = ["vqvae", "hfsq", "group"])]
    pub holistic_vq: Option<PathBuf>,
    /// Finished `soulnet_mmr` run directory (holistic model).
    #[arg(long, value_name = "RUN", requires_all = ["holistic_vq", "holistic_generator"])]
    pub holistic_mmr: Option<PathBuf>,
    /// Finished `soulnet_magm` run directory (holistic model; with --holistic-vq and
    /// --holistic-mmr, or with --holistic-model).
    #[arg(long, value_name = "RUN", conflicts_with_all = ["vqvae", "hfsq", "group"])]
    pub holistic_generator: Option<PathBuf>,
    /// A holistic model directory whose other networks, normaliser and sampling are kept: its
    /// part autoencoder replaced by --holistic-vq's (a decoder fine-tuned with `[model]
    /// decoders_only`, say) and/or its generator by --holistic-generator's (one trained with
    /// `[model] vq` and `mmr` naming this model).
    #[arg(long, value_name = "MODEL_DIR", conflicts_with = "holistic_mmr")]
    pub holistic_model: Option<PathBuf>,
    /// Model name written to model.toml (default: lodgepp-small, reactdance-small,
    /// tcdiffpp-small or soulnet-small).
    #[arg(long)]
    pub name: Option<String>,
    #[arg(long)]
    pub default_genre: Option<String>,
    /// Output model directory.
    #[arg(short, long, value_name = "DIR")]
    pub output: PathBuf,
}

#[derive(Args, Debug)]
pub struct TrainArgs {
    /// Training configuration (TOML).
    #[arg(required_unless_present = "resume", conflicts_with = "resume")]
    pub config: Option<PathBuf>,
    /// Run directory (default: the config's `[run] dir`).
    #[arg(long, value_name = "DIR", conflicts_with = "resume")]
    pub run_dir: Option<PathBuf>,
    /// Continue the run in RUN_DIR from its latest checkpoint.
    #[arg(long, value_name = "RUN_DIR")]
    pub resume: Option<PathBuf>,
    /// Stop after this step, as if interrupted (a checkpoint is written there).
    #[arg(long, value_name = "STEP")]
    pub stop_at: Option<u64>,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProtocolArg {
    /// Bailando / AIST++: 60 fps, first 1200 frames, zero-start root, frame time 1/60.
    AistppBailando,
    /// LODGE / FineDance: 30 fps, first 1024 frames, root-relative joints, 22 joints.
    FinedanceLodge,
    /// EDGE: 30 fps, 150-frame (5 s) clips, frame time 1/60.
    #[value(name = "edge-5s")]
    Edge5s,
    /// Positions as given, frame time 1/fps.
    None,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum BasVariantArg {
    Bailando,
    Lodge,
    Fact,
    Gcd,
}

#[derive(Args, Debug)]
pub struct EvalArgs {
    /// Generated motion: files or directories (any format `convert` reads, joints .npy
    /// (T, 24, 3) in metres, Y-up, or group scenes (N, T, 24, 3)).
    #[arg(long, required = true, num_args = 1..)]
    pub pred: Vec<PathBuf>,
    /// Ground-truth motion (files or directories); needed by fid_*, mpjpe, gmr, genre and the
    /// *_gt values.
    #[arg(long, num_args = 1..)]
    pub gt: Vec<PathBuf>,
    /// Duets: the leader of each --pred (follower) clip, matched by file stem. Without it, a
    /// two-dancer clip (2, T, 24, 3) is read as [leader, follower] by the duet metrics.
    #[arg(long, num_args = 1..)]
    pub leader: Vec<PathBuf>,
    /// Duets: the leader of each --gt (follower) clip, matched by file stem.
    #[arg(long, num_args = 1..)]
    pub gt_leader: Vec<PathBuf>,
    /// Evaluation protocol (no resampling: the motion must already be at its frame rate).
    #[arg(long, value_enum, default_value_t = ProtocolArg::None)]
    pub protocol: ProtocolArg,
    /// Frame rate of .npy inputs (default: the protocol's).
    #[arg(long)]
    pub fps: Option<f64>,
    /// Read every input (--pred, --gt, --leader, --gt-leader) as sampled at this rate,
    /// whatever the files' headers say (the frames stay the same, their times change); for
    /// .npy inputs, the same as --fps.
    #[arg(long, value_name = "FPS", value_parser = parse_source_fps, conflicts_with = "fps")]
    pub source_fps: Option<f64>,
    /// Comma-separated metrics (default: all that the inputs allow; duet metrics by default only
    /// with --leader): fid_k,fid_g,div_k,div_g,bas,pfc,fsr,fsd,mpjpe,penetration,gmr,gmc,tif,
    /// collision,min_distance,fid_cd,div_cd,bed,ipr,contact_range,freeze,inverted,
    /// boundary_jerk,genre, and the physical figures floor_median,floor_p05,floor_p95,float,
    /// foot_slide,jerk,jerk_p99,max_step,spikes,leg_cross,joint_speed,pelvis_speed,step_rate
    /// (world joints in metres, floor at y = 0). Groups: `physical` (those thirteen), `all`
    /// (every metric the inputs allow, the default).
    #[arg(long)]
    pub metrics: Option<String>,
    /// Genre check: the data set manifest (`dancegen dataset build`'s manifest.json) giving the
    /// genre of each --gt clip; a --gt file matches the clip whose name is its file stem.
    #[arg(long, value_name = "MANIFEST.json")]
    pub gt_genres: Option<PathBuf>,
    /// Genre check: the genre the --pred dances were asked for.
    #[arg(long, value_name = "NAME")]
    pub want_genre: Option<String>,
    /// Genre check: genres with fewer real --gt clips than this are left out of the classifier
    /// (and listed under `excluded`); 2 drops one-clip genres, whose one performance
    /// leave-one-out cannot test. The default, 1, keeps every genre.
    #[arg(long, value_name = "N", default_value_t = 1,
          value_parser = clap::value_parser!(u64).range(1..))]
    pub genre_min_clips: u64,
    /// Beat-align-score variant.
    #[arg(long, value_enum, default_value_t = BasVariantArg::Bailando)]
    pub bas_variant: BasVariantArg,
    /// Music beats: .npy of beat frame indices, or a (T, 35) feature file (beats = last column).
    #[arg(long, conflicts_with = "music")]
    pub beats: Option<PathBuf>,
    /// Song to compute the music beats from (at the motion's frame rate, 30 or 60).
    #[arg(long)]
    pub music: Option<PathBuf>,
    /// Frames between the window boundaries `boundary_jerk` looks at (the generator's window:
    /// 150 for EDGE's 5 s at 30 fps, 128 for dancegen's Lodge++).
    #[arg(long, default_value_t = 150, value_parser = clap::value_parser!(u64).range(2..))]
    pub window: u64,
    /// Write the results as JSON.
    #[arg(long, value_name = "OUT")]
    pub json: Option<PathBuf>,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum NpzStyleArg {
    /// AMASS-style SMPL: poses, trans, betas, mocap_framerate.
    Amass,
    /// EDGE's keys: smpl_poses, smpl_trans.
    Edge,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum TargetSkeleton {
    /// The 24-joint SMPL body (retargets a BVH by joint names).
    Smpl24,
}

#[derive(Args, Debug)]
pub struct ConvertArgs {
    /// Input motion: AIST++ / AIOZ-GDance .pkl, .bvh, SMPL or EDGE .npz, FineDance .npy (T, 315)
    /// or joints .npy (T, J, 3).
    pub input: PathBuf,
    /// Output; the format follows the extension: .npy (world joints (T, J, 3), float32, Y-up),
    /// .bvh, .glb, .fbx, .npz, .json.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Output frame rate (default: the input's).
    #[arg(long)]
    pub fps: Option<f32>,
    /// Read the input as sampled at this rate, whatever its header says: the frames stay the
    /// same, their times change (--fps still resamples the output). E.g. 60 for the CMU salsa
    /// BVHs, whose headers say 120. Needed for a file whose header has no rate.
    #[arg(long, value_name = "FPS", value_parser = parse_source_fps)]
    pub source_fps: Option<f64>,
    /// Retarget to this skeleton first.
    #[arg(long, value_enum)]
    pub to: Option<TargetSkeleton>,
    /// Dancer of a group file to export (single-person formats need one; .glb, .npy and .json keep every dancer unless this is given) (0-based).
    #[arg(long)]
    pub dancer: Option<usize>,
    /// Keys of an .npz output.
    #[arg(long, value_enum, default_value_t = NpzStyleArg::Amass)]
    pub npz_style: NpzStyleArg,
    /// Bone names of .bvh, .fbx and .glb output: smpl, mixamo (mixamorig:Hips, ...), ue5
    /// (pelvis, thigh_l, ...) or vrm (hips, leftUpperLeg, ...); joint positions are the same
    /// in every rig. Needs SMPL 24 motion (add --to smpl24 for a BVH).
    #[arg(long, default_value = "smpl", value_parser = parse_rig)]
    pub rig: Rig,
}

/// `--source-fps N` / `--leader-fps N`: a capture rate in (0, 1000].
fn parse_source_fps(s: &str) -> Result<f64, String> {
    let fps: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("{s:?} is not a number of frames per second"))?;
    dancegen_formats::dispatch::check_source_fps(fps)
}

/// `--rig NAME`, with the presets listed when the name is unknown.
fn parse_rig(s: &str) -> Result<Rig, String> {
    Rig::from_name(s).map_err(|e| e.to_string())
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Motion files (any format `convert` reads); each dancer of a group file is drawn too,
    /// one colour per dancer.
    #[arg(required = true)]
    pub motions: Vec<PathBuf>,
    /// Output: .png (one frame), .gif or .mp4 (needs ffmpeg on PATH).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Song to mux into an .mp4 (the video is cut to the shorter of the two).
    #[arg(long)]
    pub audio: Option<PathBuf>,
    /// Output frame rate (default: the motion's; at most 15 for .gif unless given).
    #[arg(long)]
    pub fps: Option<f32>,
    /// Read the motion files as sampled at this rate, whatever their headers say (the frames
    /// stay the same, their times change), e.g. 60 for the CMU salsa BVHs.
    #[arg(long, value_name = "FPS", value_parser = parse_source_fps)]
    pub source_fps: Option<f64>,
    /// Image width in pixels.
    #[arg(long, default_value_t = 640)]
    pub width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 480)]
    pub height: u32,
    /// .png: the frame to draw, counted at the output frame rate (default: the middle one).
    #[arg(long)]
    pub frame: Option<usize>,
    /// No anti-aliasing and no shadows (several times faster).
    #[arg(long)]
    pub draft: bool,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum SetArg {
    /// 35 dims: onset envelope, 20 MFCC, 12 chroma_cens, onset peak, beat (EDGE/Lodge/FACT).
    Edge35,
    /// 438 dims: TCDiff/TCDiff++ (MFCC + delta, chroma, onset, beat, tempogram), 60 fps only.
    Tcdiff438,
}

#[derive(Args, Debug)]
pub struct FeaturesArgs {
    /// Audio file (WAV, FLAC, OGG/Vorbis, MP3, ...). Default: the bundled demo song.
    pub audio: Option<PathBuf>,
    /// Feature frame rate: 30 (EDGE, Lodge, TCDiff; SR 15360) or 60 (FACT; SR 30720).
    #[arg(long, default_value_t = 30, value_parser = parse_fps)]
    pub fps: u32,
    /// Beat-tracker prior tempo. Default: from an AIST++ music name, else estimated at
    /// 22050 Hz as EDGE/Lodge do.
    #[arg(long, value_name = "BPM")]
    pub start_bpm: Option<f64>,
    /// Feature set.
    #[arg(long, value_enum, default_value_t = SetArg::Edge35)]
    pub set: SetArg,
    /// EDGE test-time slicing: 5 s windows (150 frames at 30 fps); `.npy` becomes (N, 150, 35).
    #[arg(long)]
    pub slice5s: bool,
    /// Stride between EDGE slices in seconds (EDGE test: 2.5, training: 0.5).
    #[arg(long, default_value_t = 2.5, requires = "slice5s")]
    pub slice_stride: f64,
    /// Output: `.npy` (float32, (T, D)) or `.json` ({fps, tempo_bpm, beat_times, onset_times, features}).
    #[arg(short, long)]
    pub output: PathBuf,
}

#[derive(Args, Debug)]
pub struct BeatsArgs {
    /// Audio file. Default: the bundled demo song.
    pub audio: Option<PathBuf>,
    /// Frame rate of the analysis (30 or 60).
    #[arg(long, default_value_t = 30, value_parser = parse_fps)]
    pub fps: u32,
    /// Beat-tracker prior tempo (default as for `features`).
    #[arg(long, value_name = "BPM")]
    pub start_bpm: Option<f64>,
    /// Write a PNG with the waveform, onset envelope, onsets and beats.
    #[arg(long, value_name = "PNG")]
    pub plot: Option<PathBuf>,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// The two frame rates of the published pipelines (see `dancegen_music::features`).
fn parse_fps(s: &str) -> Result<u32, String> {
    match s {
        "30" => Ok(30),
        "60" => Ok(60),
        _ => Err(format!(
            "{s} is not supported: use 30 (EDGE, Lodge, TCDiff) or 60 (FACT)"
        )),
    }
}

#[derive(Subcommand, Debug)]
pub enum DatasetCommand {
    /// Pair motion with music features into OUT/{motion,music}/ + OUT/manifest.json.
    Build(DatasetBuildArgs),
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum PairingArg {
    /// Time-warp each motion onto a song's beats (a pseudo-pairing, not ground truth).
    Pseudo,
    /// Couples (`<dancer>_<take>` file pairs, or two-dancer group files) time-warped by one
    /// warp per couple; one clip per role assignment, the partner under leader/.
    Duet,
    /// DD100 (Duolando) duets under --root: motion/rotmat/{train,test}/<take>_00.npy (follower)
    /// and _01.npy (leader), music/<any>/{train,test}/<take>.wav; test takes held out.
    Dd100,
    /// AIST++ layout under --root: motions/*.pkl, wav/<music id>.wav, splits/.
    Aistpp,
    /// FineDance layout under --root: motion/*.npy, music_wav/*.wav, label_json/*.json.
    Finedance,
    /// 2-5 dancers composed from the --motion takes into formations (CMU couples keep their
    /// real placement), beat-warped onto the --music songs; OUT/group/<clip>/dancer_<k>.npz.
    Group,
}

/// `FROM=TO` of `--merge-genre`.
fn parse_merge(s: &str) -> Result<(String, String), String> {
    match s.split_once('=') {
        Some((from, to)) if !from.trim().is_empty() && !to.trim().is_empty() => {
            Ok((from.trim().to_string(), to.trim().to_string()))
        }
        _ => Err(format!("{s:?}: expected FROM=TO, e.g. whirl=modern")),
    }
}

#[derive(Args, Debug)]
pub struct DatasetBuildArgs {
    /// Motion files or directories (.bvh, .pkl, .npz, .npy); BVH is retargeted to SMPL 24.
    #[arg(long, num_args = 1.., value_name = "PATH")]
    pub motion: Vec<PathBuf>,
    /// Songs to pair the motions with (pseudo pairing).
    #[arg(long, num_args = 1.., value_name = "SONG")]
    pub music: Vec<PathBuf>,
    /// Genre of every input (default: from the file names: AIST++ gXX codes; CMU subjects 05
    /// modern, 55 whirl, 60/61 salsa, 85 break).
    #[arg(long, value_name = "NAME")]
    pub genre: Option<String>,
    /// Also train on each training motion's left-right mirror image (clips `<name>_mirror`;
    /// held-out motions are not mirrored). Pseudo and duet pairing (a couple is mirrored as a
    /// whole).
    #[arg(long)]
    pub mirror: bool,
    /// Also give every clip SYNTHETIC fingers and an ARKit face made from its real body and its
    /// music (`holistic/<clip>.npz`), for the holistic system. Pseudo and aistpp pairing.
    #[arg(long)]
    pub holistic: bool,
    /// Pair each training motion with its N best songs (the further pairings are clips
    /// `<name>__<song>`; held-out motions get one). Pseudo pairing only.
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub songs_per_motion: usize,
    /// Relabel a genre after pairing, FROM=TO (repeatable), e.g. `whirl=modern` to fold a genre
    /// with too few takes to learn into a related one.
    #[arg(long = "merge-genre", value_name = "FROM=TO", value_parser = parse_merge)]
    pub merge_genre: Vec<(String, String)>,
    /// Motion or song file names (without extension) to keep out of training.
    #[arg(long = "hold-out", num_args = 1.., value_name = "STEM")]
    pub hold_out: Vec<String>,
    /// The rate a --motion input was captured at, whatever its header says (repeatable):
    /// INPUT=FPS, INPUT a --motion directory or file or a file name without extension (the
    /// most specific entry wins), or FPS alone for every input; e.g.
    /// `--source-fps ../shared/data/cmu-salsa=60`. Inputs without one are read at their
    /// header's rate. Each take's rate, kinematic tempo and floor are printed and recorded in
    /// the manifest (`takes`), and a take outside the tempo of real dance is warned about.
    #[arg(long = "source-fps", value_name = "INPUT=FPS",
          value_parser = dancegen_dataset::takes::SourceRates::parse_entry)]
    pub source_fps: Vec<(Option<String>, f64)>,
    /// How motion and music are paired.
    #[arg(long, value_enum, default_value_t = PairingArg::Pseudo)]
    pub pairing: PairingArg,
    /// Data set root for --pairing aistpp / finedance.
    #[arg(long, value_name = "DIR")]
    pub root: Option<PathBuf>,
    /// Breaks exact ties between songs; seeds the group composition.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// --pairing group: training samples to compose.
    #[arg(long, value_name = "N", default_value_t = 200)]
    pub samples: usize,
    /// --pairing group: held-out samples (from held-out takes, songs and shapes).
    #[arg(long, value_name = "N", default_value_t = 24)]
    pub held_out_samples: usize,
    /// --pairing group: length of a sample in seconds.
    #[arg(long, value_name = "SECONDS", default_value_t = 10.0)]
    pub clip_seconds: f64,
    /// --pairing group: formation shapes only held-out samples use (line, column, v,
    /// inverted_v, triangle, diamond, circle, arc, two_rows, cluster).
    #[arg(long = "hold-out-shape", num_args = 1.., value_name = "SHAPE")]
    pub hold_out_shape: Vec<String>,
    /// Output directory.
    #[arg(short, long, value_name = "OUT_DIR")]
    pub output: PathBuf,
}
