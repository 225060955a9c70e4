//! One generation library behind every dancegen front end (the CLI, the web server, batch
//! runs): a [`Request`] in — the song, the system with its options, the outputs wanted — a
//! [`Generated`] dance out, for every system.
//!
//! A job ([`Generator::run`]) finds and loads the model (cached between jobs in a
//! long-running process), analyses the song once, runs the system, and writes every output
//! through one [`output`] module that knows every format, including multi-dancer files. It
//! reports progress through a callback at least once per sampler step and honours a
//! [`CancelToken`] between steps; a cancelled or failed job leaves no output file.
//!
//! A system plugs in by implementing [`DanceSystem`] in its own module under [`systems`]
//! and adding its [`SystemRequest`] variant; nothing else changes.
//!
//! ```no_run
//! use dancegen_generate::{Generator, ModelLocator, Request, Song, SystemRequest, CancelToken};
//! use dancegen_generate::request::{CommonOptions, OutputRequest};
//!
//! let generator = Generator::new(ModelLocator::from_environment());
//! let request = Request {
//!     song: Song::Demo,
//!     system: SystemRequest::Solo(Default::default()),
//!     common: CommonOptions { seed: 1, ..Default::default() },
//!     model: None,
//!     outputs: vec![OutputRequest::new("dance.glb")],
//! };
//! let done = generator.run(&request, &|p| eprintln!("{p:?}"), &CancelToken::new())?;
//! println!("{}", done.summary);
//! # Ok::<(), dancegen_generate::GenerateError>(())
//! ```

pub mod batch_manifest;
pub mod beat_align;
pub mod edit;
pub mod error;
pub mod flags;
pub mod formation_file;
pub mod generator;
pub mod models;
pub mod output;
pub mod progress;
pub mod record;
pub mod request;
pub mod song;
pub mod system;
pub mod systems;
pub mod time_plan;

pub use error::GenerateError;
pub use generator::{Generated, Generator, KeptDance, Timings};
pub use models::ModelLocator;
pub use progress::{CancelToken, Progress};
pub use request::{Request, Song, SystemRequest};
pub use system::{Dance, DanceSystem, Dancer, Role};
