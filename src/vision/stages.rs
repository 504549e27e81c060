//! Where an analysis spends its time: exclusive wall time per stage, for `streakfit bench
//! stages`.
//!
//! A stage is entered with [`enter`] and left when its guard drops; stages nest, and a nested
//! stage's time is its own, not its parent's, so the stages of one analysis add up to its whole
//! time (what no stage claims is `other`). Nothing is recorded unless the analysis runs inside
//! [`record`] on the same thread: elsewhere a guard is a thread-local flag read and nothing
//! more, and no stage changes what the analysis computes.

use std::cell::RefCell;
use std::time::Instant;

/// The stage that time outside every named stage is booked to.
pub const OTHER: &str = "other";

struct Recorder {
    /// Exclusive milliseconds per stage, in the order first entered.
    totals: Vec<(&'static str, f64)>,
    /// The open stages, innermost last (the root is [`OTHER`]).
    open: Vec<&'static str>,
    since: Instant,
}

impl Recorder {
    /// Books the time since the last change to the innermost open stage.
    fn flush(&mut self) {
        let now = Instant::now();
        let ms = now.duration_since(self.since).as_secs_f64() * 1e3;
        self.since = now;
        let name = self.open.last().copied().unwrap_or(OTHER);
        match self.totals.iter_mut().find(|(n, _)| *n == name) {
            Some(t) => t.1 += ms,
            None => self.totals.push((name, ms)),
        }
    }
}

thread_local! {
    static RECORDER: RefCell<Option<Recorder>> = const { RefCell::new(None) };
}

/// An open stage; it closes when dropped.
#[must_use = "a stage lasts as long as its guard"]
pub struct Stage {
    on: bool,
}

/// Opens stage `name` until the returned guard drops.
pub fn enter(name: &'static str) -> Stage {
    let on = RECORDER.with(|r| match r.borrow_mut().as_mut() {
        Some(rec) => {
            rec.flush();
            rec.open.push(name);
            true
        }
        None => false,
    });
    Stage { on }
}

impl Drop for Stage {
    fn drop(&mut self) {
        if self.on {
            RECORDER.with(|r| {
                if let Some(rec) = r.borrow_mut().as_mut() {
                    rec.flush();
                    rec.open.pop();
                }
            });
        }
    }
}

/// Runs `f` as stage `name`.
pub fn within<T>(name: &'static str, f: impl FnOnce() -> T) -> T {
    let _stage = enter(name);
    f()
}

/// Runs `f` with its stages recorded: its value and the exclusive milliseconds of each stage
/// (those never entered are absent), which add up to `f`'s wall time.
pub fn record<T>(f: impl FnOnce() -> T) -> (T, Vec<(&'static str, f64)>) {
    RECORDER.with(|r| {
        *r.borrow_mut() = Some(Recorder {
            totals: Vec::new(),
            open: vec![OTHER],
            since: Instant::now(),
        })
    });
    let out = f();
    let totals = RECORDER.with(|r| {
        let mut rec = r.borrow_mut().take().expect("the recorder set above");
        rec.flush();
        rec.totals
    });
    (out, totals)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    fn busy(ms: u64) {
        let t = Instant::now();
        while t.elapsed() < Duration::from_millis(ms) {
            std::hint::spin_loop();
        }
    }

    #[test]
    fn nested_stages_book_exclusive_time_that_adds_up_to_the_whole() {
        let t = Instant::now();
        let ((), totals) = record(|| {
            busy(5);
            let _a = enter("a");
            busy(20);
            {
                let _b = enter("b");
                busy(30);
            }
            busy(10);
        });
        let whole = t.elapsed().as_secs_f64() * 1e3;
        let get = |n: &str| totals.iter().find(|(k, _)| *k == n).map(|(_, v)| *v);
        let (a, b, other) = (get("a").unwrap(), get("b").unwrap(), get(OTHER).unwrap());
        // Each holds at least its own busy time (a preempted thread only adds to it)...
        assert!(
            a >= 30.0 && b >= 30.0 && other >= 5.0,
            "a {a} b {b} other {other}"
        );
        // ...and no more: `a` does not hold `b`'s 30 ms as well, nothing is lost or counted
        // twice.
        let sum = a + b + other;
        assert!(sum <= whole && sum > whole - 1.0, "{sum} of {whole}");
    }

    #[test]
    fn outside_a_recording_a_stage_records_nothing() {
        {
            let _s = enter("x");
        }
        let ((), totals) = record(|| ());
        assert!(totals.iter().all(|(n, _)| *n == OTHER), "{totals:?}");
    }
}
