//! Each replica's sessions' carries ([`Carry`]): what a step kept for its
//! session's next step, held by session id under a byte budget
//! (`--session-carry-mb`), the least recently used dropped first, and
//! none longer than a session lives idle (`--session-ttl-s`). The
//! sessions' store drops a session's carry when the session ends here.
//!
//! A carry is a cache: it is checked against the step's state before use
//! (see [`Carry`]), so one that another replica's steps made stale, or that
//! was dropped, costs a step that starts over, never a different plan. It
//! is not stored in the database; a step on another replica builds its own.

use std::collections::{BTreeMap, HashMap};
use std::sync::{Mutex, PoisonError};
use std::time::{Duration, Instant};

use crate::estimator::Carry;
use crate::metric_names;

/// The carries of this replica's sessions.
#[derive(Debug)]
pub struct Carries {
    limit: usize,
    ttl: Duration,
    held: Mutex<Held>,
}

#[derive(Debug, Default)]
struct Held {
    bytes: usize,
    tick: u64,
    /// By session id: when it was last kept, its carry and its bytes.
    by_id: HashMap<String, Kept>,
    /// Session ids by when they were last kept, oldest first.
    order: BTreeMap<u64, String>,
}

struct Kept {
    tick: u64,
    at: Instant,
    carry: Carry,
    bytes: usize,
}

impl std::fmt::Debug for Kept {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Kept")
            .field("tick", &self.tick)
            .field("bytes", &self.bytes)
            .finish()
    }
}

impl Carries {
    /// No carries, at most `limit` bytes of them (0: none kept), none
    /// kept longer than `ttl` (its session's idle time to live: a session
    /// that has not stepped for that long is gone).
    pub fn new(limit: usize, ttl: Duration) -> Self {
        Self {
            limit,
            ttl,
            held: Mutex::new(Held::default()),
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Held> {
        // Every update leaves the maps consistent: a panic elsewhere
        // poisons nothing that matters.
        self.held.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Session `id`'s carry, taken out (an empty one if none is held).
    pub fn take(&self, id: &str) -> Carry {
        let mut held = self.lock();
        self.expire(&mut held);
        let Some(kept) = held.by_id.remove(id) else {
            return Carry::new();
        };
        held.order.remove(&kept.tick);
        held.bytes -= kept.bytes;
        Self::report(&held);
        kept.carry
    }

    /// Keeps `carry` for session `id`'s next step, dropping the least
    /// recently kept carries past the budget (an empty carry, or one larger
    /// than the whole budget, is not kept).
    pub fn keep(&self, id: &str, carry: Carry) {
        let bytes = carry.memory_bytes();
        let mut held = self.lock();
        self.expire(&mut held);
        if let Some(old) = held.by_id.remove(id) {
            held.order.remove(&old.tick);
            held.bytes -= old.bytes;
        }
        if !carry.is_empty() && bytes <= self.limit {
            while held.bytes + bytes > self.limit {
                let Some((_, oldest)) = held.order.pop_first() else {
                    break;
                };
                if let Some(dropped) = held.by_id.remove(&oldest) {
                    held.bytes -= dropped.bytes;
                }
            }
            held.tick += 1;
            let tick = held.tick;
            held.order.insert(tick, id.to_string());
            held.by_id.insert(
                id.to_string(),
                Kept {
                    tick,
                    at: Instant::now(),
                    carry,
                    bytes,
                },
            );
            held.bytes += bytes;
        }
        Self::report(&held);
    }

    /// Drops session `id`'s carry (the session ended).
    pub fn forget(&self, id: &str) {
        drop(self.take(id));
    }

    /// Drops the carries kept longer ago than the time to live (the
    /// oldest come first).
    fn expire(&self, held: &mut Held) {
        let now = Instant::now();
        while let Some((_, id)) = held.order.first_key_value() {
            let Some(kept) = held.by_id.get(id) else {
                break;
            };
            if now.duration_since(kept.at) <= self.ttl {
                break;
            }
            if let Some((_, id)) = held.order.pop_first()
                && let Some(gone) = held.by_id.remove(&id)
            {
                held.bytes -= gone.bytes;
            }
        }
    }

    /// Bytes held now.
    pub fn bytes(&self) -> usize {
        let mut held = self.lock();
        self.expire(&mut held);
        Self::report(&held);
        held.bytes
    }

    fn report(held: &Held) {
        metrics::gauge!(metric_names::SESSION_CARRY_BYTES).set(held.bytes as f64);
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::cancel::CancelToken;
    use crate::planner::{PlanInput, PlanRequest, Planner};
    use crate::scenario::builtins;

    /// The carry of a plan on `paper-v10` with one step of history, the
    /// sensor at `x`.
    pub(crate) fn carry(planner: &Planner, x: f64) -> Carry {
        let req: PlanRequest = serde_json::from_value(serde_json::json!({
            "sensors": [{"id": "a", "x": x, "y": 150.0}],
            "history": [[{"x": x, "y": 140.0}]],
        }))
        .expect("a plan request");
        let input = PlanInput::new(&planner.scenario, &req).expect("valid");
        let mut carry = Carry::new();
        planner
            .plan_carried(&input, &CancelToken::never(), &mut carry)
            .expect("never cancelled");
        assert!(!carry.is_empty());
        carry
    }

    #[test]
    fn the_least_recently_kept_carry_goes_first_past_the_budget() {
        let planner = Planner::new(builtins().remove(0));
        let one = carry(&planner, 150.0).memory_bytes();
        // Room for two carries of about this size, not three.
        let hour = Duration::from_secs(3600);
        let carries = Carries::new(2 * one + one / 2, hour);
        carries.keep("a", carry(&planner, 150.0));
        carries.keep("b", carry(&planner, 160.0));
        assert!(carries.bytes() > one);
        // Taking "a" and keeping it again makes "b" the oldest.
        let a = carries.take("a");
        assert!(!a.is_empty());
        carries.keep("a", a);
        carries.keep("c", carry(&planner, 170.0));
        assert!(
            carries.take("b").is_empty(),
            "b was the least recently kept"
        );
        assert!(!carries.take("c").is_empty());
        assert!(carries.bytes() <= 2 * one + one / 2);
        carries.forget("a");
        assert_eq!(carries.bytes(), 0);
        // Nothing is kept past a budget smaller than one carry.
        let none = Carries::new(one / 2, hour);
        none.keep("a", carry(&planner, 150.0));
        assert!(none.take("a").is_empty());
        assert_eq!(none.bytes(), 0);
        // Nor past the time to live.
        let brief = Carries::new(4 * one, Duration::from_millis(50));
        brief.keep("a", carry(&planner, 150.0));
        assert!(brief.bytes() > 0);
        std::thread::sleep(Duration::from_millis(80));
        assert_eq!(brief.bytes(), 0);
        assert!(brief.take("a").is_empty());
    }
}
