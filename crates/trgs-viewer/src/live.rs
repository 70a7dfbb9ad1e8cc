//! Live training in the viewer: the training thread publishes snapshots of its parameters into a
//! [`LiveFeed`], and the viewer shows the newest. The trainer only reads its scene back when the
//! viewer has taken the previous snapshot and a minimum interval has passed, so a slow viewer
//! never slows training by more than one readback per interval.
use std::path::PathBuf;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};
use trgs_core::pipeline::ReflectionModel;
use trgs_core::scene::{Camera, Gaussians, ReflectionPlane};

/// The model at one point of training.
#[derive(Clone, Debug)]
pub struct Snapshot {
    pub gaussians: Gaussians<f32>,
    pub planes: Vec<ReflectionPlane>,
    /// The reflection model training uses (its ablations).
    pub reflection: ReflectionModel,
    /// A line for the viewer, e.g. "step 1200 of 2000, loss 0.031, 81k Gaussians".
    pub status: String,
}

#[derive(Debug, Default)]
struct State {
    cameras: Vec<Camera>,
    /// The run's folder (where screenshots go).
    folder: Option<PathBuf>,
    snapshot: Option<Snapshot>,
    /// Bumped by each publish.
    generation: u64,
    /// The generation the viewer last took.
    taken: u64,
    published_at: Option<Instant>,
    status: String,
    viewer_closed: bool,
}

/// Shared between the training thread and the viewer; cloning shares it.
#[derive(Clone, Debug, Default)]
pub struct LiveFeed(Arc<Mutex<State>>);

impl LiveFeed {
    pub fn new() -> Self {
        Self::default()
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        // A panic on the other side must not take this side down too.
        self.0.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// The training views (the viewer snaps to them).
    pub fn set_cameras(&self, cameras: Vec<Camera>) {
        self.lock().cameras = cameras;
    }

    /// The run's folder: the viewer saves screenshots under its `screenshots/`.
    pub fn set_folder(&self, folder: PathBuf) {
        self.lock().folder = Some(folder);
    }

    pub fn folder(&self) -> Option<PathBuf> {
        self.lock().folder.clone()
    }

    /// Whether the trainer should publish now: the viewer is open, has taken the last snapshot,
    /// and `interval` has passed since it.
    pub fn wants_snapshot(&self, interval: Duration) -> bool {
        let s = self.lock();
        !s.viewer_closed
            && s.taken == s.generation
            && s.published_at.is_none_or(|t| t.elapsed() >= interval)
    }

    pub fn publish(&self, snapshot: Snapshot) {
        let mut s = self.lock();
        s.status = snapshot.status.clone();
        s.snapshot = Some(snapshot);
        s.generation += 1;
        s.published_at = Some(Instant::now());
    }

    /// A status line without a new model (e.g. "training finished").
    pub fn set_status(&self, status: impl Into<String>) {
        self.lock().status = status.into();
    }

    /// The newest snapshot if the viewer has not taken it yet.
    pub fn take(&self) -> Option<Snapshot> {
        let mut s = self.lock();
        s.taken = s.generation;
        s.snapshot.take()
    }

    pub fn cameras(&self) -> Vec<Camera> {
        self.lock().cameras.clone()
    }

    pub fn status(&self) -> String {
        self.lock().status.clone()
    }

    /// The viewer window closed: stop publishing (training goes on).
    pub fn close(&self) {
        self.lock().viewer_closed = true;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn snap(status: &str) -> Snapshot {
        Snapshot {
            gaussians: Gaussians::empty(0),
            planes: Vec::new(),
            reflection: ReflectionModel::default(),
            status: status.into(),
        }
    }

    #[test]
    fn publishes_only_what_the_viewer_is_ready_for() {
        let feed = LiveFeed::new();
        assert!(feed.wants_snapshot(Duration::ZERO));
        feed.publish(snap("a"));
        assert!(!feed.wants_snapshot(Duration::ZERO), "the last one is not taken yet");
        assert_eq!(feed.take().map(|s| s.status), Some("a".into()));
        assert!(feed.take().is_none(), "a snapshot is taken once");
        assert!(feed.wants_snapshot(Duration::ZERO));
        assert!(!feed.wants_snapshot(Duration::from_secs(3600)), "interval not passed");
        feed.close();
        assert!(!feed.wants_snapshot(Duration::ZERO), "nobody is watching");
    }
}
