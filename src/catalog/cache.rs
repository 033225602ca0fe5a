//! Planners of scenarios sent inline to `POST /v1/plan`, kept in a
//! least-recently-used cache bounded by memory, so any replica can serve any
//! request without shared state.

use std::sync::{Arc, Mutex, PoisonError};

use lru::LruCache;

use crate::planner::Planner;

/// An LRU cache of planners by scenario id, bounded by their memory.
#[derive(Debug)]
pub struct PlannerCache {
    inner: Mutex<Inner>,
    capacity: usize,
}

#[derive(Debug)]
struct Inner {
    planners: LruCache<String, Arc<Planner>>,
    bytes: usize,
}

impl PlannerCache {
    /// A cache holding at most `capacity` bytes of planners (a planner larger
    /// than that is served but not kept).
    pub fn new(capacity: usize) -> Self {
        PlannerCache {
            inner: Mutex::new(Inner {
                planners: LruCache::unbounded(),
                bytes: 0,
            }),
            capacity,
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Inner> {
        self.inner.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// The planner of a scenario, marking it recently used.
    pub fn get(&self, id: &str) -> Option<Arc<Planner>> {
        self.lock().planners.get(id).cloned()
    }

    /// Keeps a planner, evicting the least recently used ones to fit.
    /// Returns the planner cached under its id (an earlier one stays).
    pub fn insert(&self, planner: Arc<Planner>) -> Arc<Planner> {
        let size = planner.memory_bytes();
        let mut inner = self.lock();
        if let Some(existing) = inner.planners.get(&planner.scenario.id) {
            return existing.clone();
        }
        if size > self.capacity {
            return planner;
        }
        while inner.bytes + size > self.capacity {
            match inner.planners.pop_lru() {
                Some((_, old)) => inner.bytes -= old.memory_bytes(),
                None => break,
            }
        }
        inner.bytes += size;
        inner
            .planners
            .put(planner.scenario.id.clone(), planner.clone());
        planner
    }

    /// Drops the planner of `id`, if held.
    pub fn remove(&self, id: &str) {
        let mut inner = self.lock();
        if let Some(old) = inner.planners.pop(id) {
            inner.bytes -= old.memory_bytes();
        }
    }

    /// The ids of the planners held.
    pub fn ids(&self) -> Vec<String> {
        self.lock()
            .planners
            .iter()
            .map(|(id, _)| id.clone())
            .collect()
    }

    /// Planners held and their bytes.
    pub fn usage(&self) -> (usize, usize) {
        let inner = self.lock();
        (inner.planners.len(), inner.bytes)
    }
}
