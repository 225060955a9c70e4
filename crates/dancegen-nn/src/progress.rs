//! Progress and cancellation inside long inference loops (denoising steps, token windows).
//!
//! Samplers call a [`StepHook`] after every unit of work; the hook reports progress and may
//! answer [`ControlFlow::Break`] to stop the run, which the sampler turns into [`Cancelled`].
//! The hook lives here, next to the samplers, so every system reports through the same type
//! and a front end (CLI progress bar, web server job) needs no knowledge of any sampler.

use std::ops::ControlFlow;

/// Told after each finished unit of a named part of a run (`"denoising"`, `"choreography"`).
///
/// `done` counts up to `total` within the part; a part may be reported again from 0 when a
/// system runs it more than once (it then says so in its own docs).
pub trait StepHook: Sync {
    fn on_step(&self, part: &'static str, done: usize, total: usize) -> ControlFlow<()>;
}

impl<F> StepHook for F
where
    F: Fn(&'static str, usize, usize) -> ControlFlow<()> + Sync,
{
    fn on_step(&self, part: &'static str, done: usize, total: usize) -> ControlFlow<()> {
        self(part, done, total)
    }
}

/// The part name of diffusion sampling steps (every system's sampler reports under it).
pub const DENOISING: &str = "denoising";

/// A hook that never stops anything (for callers that want neither progress nor cancel).
pub struct NoHook;

impl StepHook for NoHook {
    fn on_step(&self, _: &'static str, _: usize, _: usize) -> ControlFlow<()> {
        ControlFlow::Continue(())
    }
}

/// The run was stopped by its [`StepHook`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("cancelled")]
pub struct Cancelled;

/// `hook.on_step(..)` as a `Result`, for `?` in sampling loops.
pub fn step(
    hook: &dyn StepHook,
    part: &'static str,
    done: usize,
    total: usize,
) -> Result<(), Cancelled> {
    match hook.on_step(part, done, total) {
        ControlFlow::Continue(()) => Ok(()),
        ControlFlow::Break(()) => Err(Cancelled),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

    #[test]
    fn closures_are_hooks_and_break_cancels() {
        let seen = AtomicUsize::new(0);
        let hook = |_: &'static str, done: usize, _: usize| {
            seen.store(done, Ordering::Relaxed);
            if done >= 2 {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        };
        assert_eq!(step(&hook, "x", 1, 5), Ok(()));
        assert_eq!(step(&hook, "x", 2, 5), Err(Cancelled));
        assert_eq!(seen.load(Ordering::Relaxed), 2);
        assert_eq!(step(&NoHook, "x", 9, 5), Ok(()));
    }
}
