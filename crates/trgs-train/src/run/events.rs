//! What a run reports, in the order it happens: the events an app, the `train` command's progress
//! bar and the live viewer read.
use super::outputs::RunSummary;
use crate::eval::Evaluation;
use crate::trainer::StepStats;
use crate::trainer::memory::GpuMemory;
use std::path::PathBuf;
use trgs_core::scene::ReflectionPlane;

/// What a run reports, in the order it happens.
#[derive(Clone, Debug)]
pub enum RunEvent {
    /// A line about the set-up: the dataset, the planes to come, a resumed or replaced run.
    Note(String),
    /// A training step finished.
    Step(StepEvent),
    /// A plane was initialised from the glass masks at the end of stage 1.
    PlaneCreated { label: u32, plane: ReflectionPlane },
    /// A glass label's plane could not be fitted.
    PlaneFailed { label: u32, reason: String },
    /// The test views were evaluated.
    Evaluation(Evaluation),
    /// A checkpoint was written: the run can be continued from here.
    CheckpointWritten { step: u32, path: PathBuf },
    /// The outputs are written; the run is over.
    Finished(RunSummary),
}

/// One finished step.
#[derive(Clone, Debug)]
pub struct StepEvent {
    /// Steps taken so far (this one included) and planned.
    pub step: u32,
    pub iterations: u32,
    /// The training view of the step.
    pub view: String,
    pub gaussians: u32,
    pub stats: StepStats,
    /// The trainer's GPU buffers after the step and the process's peak RAM so far.
    pub memory: StepMemory,
}

/// Memory after a step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepMemory {
    pub gpu: GpuMemory,
    /// None where the system does not report it (`peak_ram_bytes` of `trainer::memory`).
    pub peak_ram_bytes: Option<u64>,
}
