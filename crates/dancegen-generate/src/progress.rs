//! Job progress (stage, overall fraction, estimated seconds left) and cancellation.
//!
//! A job is a fixed plan of stages, each with a share of the whole: loading the model,
//! analysing the song, the system's own parts (GPT tokens, denoising steps; see
//! [`crate::DanceSystem::PARTS`]) and writing the outputs. Within a stage the system or the
//! writer reports `done / total`; the [`Tracker`] maps that onto the whole, never lets the
//! fraction go back, and calls the job's callback at most once per 0.1 % of progress (plus
//! every stage change and the final 1.0). The remaining time is extrapolated from the time
//! spent so far: the shares are estimates, so the ETA gets better as the job advances.

use std::ops::ControlFlow;
use std::sync::Arc;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use dancegen_nn::progress::StepHook;

use crate::error::GenerateError;

/// Stage names, as they appear in [`Progress::stage`] and in `--progress json`.
pub mod stage {
    pub const LOAD_MODEL: &str = "load_model";
    pub const ANALYSE_SONG: &str = "analyse_song";
    pub const WRITE_OUTPUTS: &str = "write_outputs";
    /// Rendering a video preview: part of [`WRITE_OUTPUTS`]'s share, named apart so a user
    /// sees why saving takes as long as the dance.
    pub const RENDER_VIDEO: &str = "render_video";
    pub const DONE: &str = "done";
}

/// One progress report.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Progress {
    /// What the job is doing: a [`stage`] name or one of the system's parts
    /// (`"choreography"`, `"denoising"`).
    pub stage: &'static str,
    /// Share of the whole job done, 0..=1, never decreasing; the last report has 1.
    pub fraction: f64,
    /// Estimated seconds left (`None` until there is enough progress to extrapolate from).
    pub eta_s: Option<f64>,
}

/// Stops a running job from another thread (a server's cancel button, Ctrl-C). Checked after
/// every sampler step, between stages and between preview frames.
#[derive(Clone, Debug, Default)]
pub struct CancelToken(Arc<AtomicBool>);

impl CancelToken {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn cancel(&self) {
        self.0.store(true, Ordering::SeqCst);
    }

    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }
}

/// Smallest fraction increase that is reported (0.1 %).
const REPORT_STEP: f64 = 1e-3;
/// Progress below which no ETA is given (too little to extrapolate from).
const ETA_MIN_FRACTION: f64 = 0.02;

/// The ETA extrapolates the progress made over about this many seconds, not since the start:
/// the stages run at different speeds against their planned shares, so the early ones (the
/// song's analysis) said little of the dance's pace. On a 288 s song, extrapolating from the
/// start said 23 s left at 26 % with 52 s to go.
const ETA_WINDOW_S: f64 = 8.0;

struct State {
    fraction: f64,
    reported: f64,
    stage: &'static str,
    /// `(elapsed seconds, fraction)` of recent reports, oldest first, spanning a little more
    /// than [`ETA_WINDOW_S`].
    recent: std::collections::VecDeque<(f64, f64)>,
}

/// Maps stage-local progress onto the whole job and forwards it to the job's callback.
pub struct Tracker<'a> {
    /// `(stage, share)` in job order; shares sum to 1.
    plan: Vec<(&'static str, f64)>,
    callback: &'a (dyn Fn(&Progress) + Sync),
    cancel: &'a CancelToken,
    started: Instant,
    state: Mutex<State>,
}

impl<'a> Tracker<'a> {
    /// A tracker over `plan` (`(stage, weight)`, normalised here; a zero-weight stage still
    /// reports its name).
    pub fn new(
        plan: Vec<(&'static str, f64)>,
        callback: &'a (dyn Fn(&Progress) + Sync),
        cancel: &'a CancelToken,
    ) -> Self {
        let sum: f64 = plan.iter().map(|(_, w)| w.max(0.0)).sum();
        let plan = plan
            .into_iter()
            .map(|(s, w)| (s, if sum > 0.0 { w.max(0.0) / sum } else { 0.0 }))
            .collect();
        Tracker {
            plan,
            callback,
            cancel,
            started: Instant::now(),
            state: Mutex::new(State {
                fraction: 0.0,
                reported: -1.0,
                stage: "",
                recent: std::collections::VecDeque::new(),
            }),
        }
    }

    /// `Err(Cancelled)` once the job's token is set.
    pub fn check(&self) -> Result<(), GenerateError> {
        if self.cancel.is_cancelled() {
            Err(GenerateError::Cancelled)
        } else {
            Ok(())
        }
    }

    /// `done / total` of `stage` finished. Unknown stages only change the reported name.
    pub fn advance(&self, stage: &'static str, done: usize, total: usize) {
        self.advance_as(stage, stage, done, total);
    }

    /// [`Self::advance`] of `stage`, reported under the name `shown` (a step of a stage that
    /// deserves its own words, such as [`stage::RENDER_VIDEO`] inside the outputs).
    pub fn advance_as(&self, shown: &'static str, stage: &'static str, done: usize, total: usize) {
        let local = if total == 0 {
            1.0
        } else {
            (done as f64 / total as f64).clamp(0.0, 1.0)
        };
        let mut before = 0.0;
        let mut at = None;
        for &(s, share) in &self.plan {
            if s == stage {
                at = Some(before + share * local);
                break;
            }
            before += share;
        }
        let mut st = self.state.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(f) = at {
            // Never backwards (a stage reported again, rounding).
            st.fraction = st.fraction.max(f.min(1.0));
        }
        let changed = st.stage != shown;
        if changed || st.fraction >= st.reported + REPORT_STEP {
            st.stage = shown;
            st.reported = st.fraction;
            let p = self.progress(shown, &mut st);
            drop(st);
            (self.callback)(&p);
        }
    }

    /// The start of `stage` (0 of it done).
    pub fn begin(&self, stage: &'static str) -> Result<(), GenerateError> {
        self.check()?;
        self.advance(stage, 0, 1);
        Ok(())
    }

    /// The final report: stage [`stage::DONE`], fraction 1, no time left.
    pub fn finish(&self) {
        let mut st = self.state.lock().unwrap_or_else(|e| e.into_inner());
        st.fraction = 1.0;
        st.reported = 1.0;
        st.stage = stage::DONE;
        drop(st);
        (self.callback)(&Progress {
            stage: stage::DONE,
            fraction: 1.0,
            eta_s: Some(0.0),
        });
    }

    fn progress(&self, stage: &'static str, st: &mut State) -> Progress {
        progress_at(stage, st, self.started.elapsed().as_secs_f64())
    }
}

/// The report of `stage` with `st.fraction` done `elapsed` seconds into the job; the ETA
/// extrapolates the pace of the last [`ETA_WINDOW_S`] seconds (since the start while the
/// job is younger).
fn progress_at(stage: &'static str, st: &mut State, elapsed: f64) -> Progress {
    let fraction = st.fraction;
    st.recent.push_back((elapsed, fraction));
    // Keep one sample at least ETA_WINDOW_S old, as the window's start.
    while st.recent.len() > 2 && elapsed - st.recent[1].0 >= ETA_WINDOW_S {
        st.recent.pop_front();
    }
    let (t0, f0) = st.recent[0];
    let rate = if elapsed - t0 >= ETA_WINDOW_S && fraction > f0 {
        (fraction - f0) / (elapsed - t0)
    } else {
        fraction / elapsed.max(1e-9)
    };
    // None before a window's worth of pace is known: the first seconds (model, song) said
    // 24 s left on a 61 s job.
    let eta_s = ((ETA_MIN_FRACTION..1.0).contains(&fraction) && elapsed >= ETA_WINDOW_S)
        .then(|| (1.0 - fraction) / rate.max(1e-12));
    Progress {
        stage,
        fraction,
        eta_s,
    }
}

/// Samplers report through the tracker: every step is progress, and a set token stops them.
impl StepHook for Tracker<'_> {
    fn on_step(&self, part: &'static str, done: usize, total: usize) -> ControlFlow<()> {
        self.advance(part, done, total);
        if self.cancel.is_cancelled() {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A job whose first 8 s make 30 % (a fast analysis) and which then goes at 1 % a
    /// second: after the window the ETA follows the slow pace (70 s left at 30 %, not the
    /// 19 s the start's pace says), and it stays within 1 s of the truth from then on.
    #[test]
    fn the_eta_follows_the_recent_pace() {
        let mut st = State {
            fraction: 0.0,
            reported: -1.0,
            stage: "",
            recent: std::collections::VecDeque::new(),
        };
        let truth = |t: f64| {
            if t <= 8.0 {
                0.3 * t / 8.0
            } else {
                0.3 + 0.01 * (t - 8.0)
            }
        };
        let mut etas = Vec::new();
        for i in 1..=150 {
            let t = f64::from(i) * 0.5;
            st.fraction = truth(t);
            etas.push((t, progress_at("x", &mut st, t).eta_s));
        }
        let end = 8.0 + 70.0;
        for &(t, eta) in &etas {
            if t >= 8.0 + ETA_WINDOW_S && t < end {
                let eta = eta.expect("an ETA while running");
                assert!((t + eta - end).abs() < 1.0, "at {t} s the ETA says {eta} s");
            }
        }
        // Nothing is said before a window's worth of pace is known.
        assert!(
            etas.iter()
                .all(|(t, eta)| *t >= ETA_WINDOW_S || eta.is_none())
        );
        // From the start's pace it would have said 8 / 0.3 × 0.7 ≈ 18.7 s at 8 s.
        let mut fresh = State {
            recent: std::collections::VecDeque::new(),
            ..st
        };
        fresh.fraction = 0.3;
        let early = progress_at("x", &mut fresh, 8.0).eta_s.unwrap();
        assert!((early - 18.67).abs() < 0.01, "{early}");
    }

    #[test]
    fn fractions_follow_the_plan_and_never_go_back() {
        let seen = Mutex::new(Vec::<Progress>::new());
        let cb = |p: &Progress| seen.lock().unwrap().push(p.clone());
        let cancel = CancelToken::new();
        let t = Tracker::new(vec![("a", 1.0), ("b", 3.0)], &cb, &cancel);
        t.advance("a", 1, 2);
        t.advance("b", 1, 3);
        t.advance("b", 0, 3); // reported again from 0: must not go back
        t.advance("b", 3, 3);
        t.finish();
        let s = seen.lock().unwrap();
        let f: Vec<f64> = s.iter().map(|p| p.fraction).collect();
        assert!((f[0] - 0.125).abs() < 1e-12, "{f:?}");
        assert!((f[1] - 0.5).abs() < 1e-12, "{f:?}");
        assert!(f.windows(2).all(|w| w[1] >= w[0]), "{f:?}");
        assert_eq!(*f.last().unwrap(), 1.0);
        assert_eq!(s.last().unwrap().stage, stage::DONE);
    }

    #[test]
    fn a_set_token_breaks_the_sampler() {
        let cb = |_: &Progress| {};
        let cancel = CancelToken::new();
        let t = Tracker::new(vec![("a", 1.0)], &cb, &cancel);
        assert_eq!(t.on_step("a", 1, 4), ControlFlow::Continue(()));
        cancel.clone().cancel();
        assert_eq!(t.on_step("a", 2, 4), ControlFlow::Break(()));
        assert!(matches!(t.check(), Err(GenerateError::Cancelled)));
    }
}
