//! The run's steps: each recorded, then the one before it finished and reported, with the
//! plane initialisation, evaluation and checkpoint that fall on them.
use super::{CHECKPOINT_FILE, PlaneSource, RunEvent, StepEvent, StepMemory, TrainingRun, outputs};
use crate::eval::evaluate;
use crate::trainer::StepStats;
use anyhow::{Result, bail};
use std::time::{Duration, Instant};
use trgs_render::GpuError;

/// A step recorded and not yet finished, with its view and what its maintenance did.
#[derive(Debug)]
pub(super) struct InFlight {
    step: crate::trainer::StepInFlight,
    vi: usize,
    maintained: (Vec<crate::densify::DensifyEvent>, usize),
}

impl TrainingRun {
    /// One step, with the plane initialisation, evaluation and checkpoint that fall on it.
    ///
    /// Steps are pipelined: a step is recorded, then the previous one is finished (its loss and
    /// plane gradients read back) and reported, then the new one's maintenance runs, so that the
    /// GPU has the new step queued while the CPU reads the previous one. A densification the
    /// maintenance decides is applied at the next step's maintenance, when its counters are
    /// back ([`crate::trainer::Trainer::maintain`]). A step that evaluates, checkpoints or ends
    /// the run is taken whole, after the one in flight is finished, and applies what its
    /// maintenance decides at once (as the planes' initialisation does first).
    pub(super) fn advance(&mut self) -> Result<()> {
        let iterations = self.config().iterations;
        let t = &self.trainer;
        let auto = self.config().planes == Some(PlaneSource::Auto);
        let at_stage1_end = t.step == t.settings.stage1 && t.planes().is_empty();
        let masks = at_stage1_end && !self.data.materials.is_empty();
        let propose = auto && t.planes().is_empty() && self.state.next_proposal == Some(t.step);
        let decide = self.state.trial.as_ref().is_some_and(|trial| t.step >= trial.decide_after);
        if masks || propose || decide {
            // The planes start (or change) from the set with any densification still pending
            // applied, reported with the step in flight (whose maintenance decided it).
            let settled = self.trainer.settle()?;
            if let Some(f) = self.in_flight.as_mut() {
                f.maintained.0.extend(settled.0);
                f.maintained.1 += settled.1;
            }
            self.finish_in_flight()?;
            // Part of training: it counts in the time that PSNR is reported against.
            let ti = Instant::now();
            if masks {
                self.init_planes()?;
            } else {
                if propose {
                    self.propose_planes()?;
                } else {
                    self.decide_trial()?;
                }
                self.state.candidate_seconds += ti.elapsed().as_secs_f64();
            }
            self.state.train_seconds += ti.elapsed().as_secs_f64();
        }
        // After the planes' start: a trial holds views out of the order.
        self.draw_epoch_if_done();
        let Some(vi) = self.state.order.pop() else {
            bail!("{}: no training views", self.data_dir.display())
        };
        let next = self.trainer.step + 1;
        let eval_now = next.is_multiple_of(self.eval_every) || next == iterations;
        let checkpoint_now = next.is_multiple_of(self.checkpoint_every) && next < iterations;
        if eval_now || checkpoint_now {
            self.finish_in_flight()?;
            self.whole_step(vi, eval_now)?;
        } else {
            self.pipelined_step(vi)?;
        }
        if checkpoint_now {
            self.save_checkpoint()?;
        }
        Ok(())
    }

    /// Step `self.trainer.step + 1` on view `vi`, taken whole (`train_step_then`), evaluated
    /// before its maintenance when `eval_now`.
    fn whole_step(&mut self, vi: usize, eval_now: bool) -> Result<()> {
        let ts = Instant::now();
        let next = self.trainer.step + 1;
        let (mut evaluation, mut eval_time) = (None, Duration::ZERO);
        let before = self.state.train_seconds;
        let data = &self.data;
        let stats = self.trainer.train_step_then(&data.train[vi], |t| {
            // Before the step's densification, reset or perturbation (see train_step_then).
            if eval_now {
                let te = Instant::now();
                let seconds = before + ts.elapsed().as_secs_f64();
                evaluation = Some(evaluate(&outputs::model_of(t), data, t.step, seconds)?);
                eval_time = te.elapsed();
            }
            Ok(())
        });
        let stats = stats.and_then(|stats| self.prefetch_next().map(|()| stats));
        let stats = stats.map_err(|e| self.stopped_at(e, next))?;
        self.state.train_seconds += ts.elapsed().saturating_sub(eval_time).as_secs_f64();
        self.report_step(vi, stats)?;
        if let Some(e) = evaluation {
            self.log.evaluation(&e)?;
            self.state.evaluations.push(e.clone());
            self.events.push_back(RunEvent::Evaluation(e));
        }
        Ok(())
    }

    /// Record step `self.trainer.step + 1` on view `vi`, finish and report the step in flight,
    /// then run the new step's maintenance; the new step stays in flight.
    fn pipelined_step(&mut self, vi: usize) -> Result<()> {
        let ts = Instant::now();
        let next = self.trainer.step + 1;
        let recorded = self.trainer.record_step(&self.data.train[vi]);
        let recorded = recorded.and_then(|r| self.prefetch_next().map(|()| r));
        let recorded = recorded.map_err(|e| self.stopped_at(e, next))?;
        self.state.train_seconds += ts.elapsed().as_secs_f64();
        self.finish_in_flight()?;
        let ts = Instant::now();
        let maintained = self.trainer.maintain().map_err(|e| self.stopped_at(e, next))?;
        self.state.train_seconds += ts.elapsed().as_secs_f64();
        self.in_flight = Some(InFlight { step: recorded, vi, maintained });
        Ok(())
    }

    /// Finish and report the step in flight, if any.
    pub(super) fn finish_in_flight(&mut self) -> Result<()> {
        let Some(InFlight { step, vi, maintained }) = self.in_flight.take() else {
            return Ok(());
        };
        let ts = Instant::now();
        let n = step.step();
        let mut stats = self.trainer.finish_step(step).map_err(|e| self.stopped_at(e, n))?;
        self.state.train_seconds += ts.elapsed().as_secs_f64();
        (stats.densified, stats.perturbed) = maintained;
        self.report_step(vi, stats)
    }

    /// Queue the next view's upload now, ahead of its step (a no-op when every view fits the
    /// budget and it is resident); after an epoch's last step, the next epoch's order is drawn
    /// now so that its first view is uploaded ahead too.
    fn prefetch_next(&mut self) -> Result<()> {
        if self.trainer.step < self.config().iterations {
            self.draw_epoch_if_done();
        }
        match self.state.order.last() {
            Some(&next) => self.trainer.prefetch(&self.data.train[next]),
            None => Ok(()),
        }
    }

    /// Log and report a finished step on view `vi`.
    fn report_step(&mut self, vi: usize, stats: StepStats) -> Result<()> {
        self.state.phase_ms.accumulate(&stats.times);
        self.state.skipped_steps += u32::from(stats.skipped);
        let gaussians = self.trainer.scene().len();
        let view = self.data.train[vi].camera.name.clone();
        let memory = StepMemory {
            gpu: self.trainer.gpu_memory(),
            peak_ram_bytes: crate::trainer::memory::peak_ram_bytes(),
        };
        self.state.peak_gpu_bytes = self.state.peak_gpu_bytes.max(memory.gpu.total());
        let (step, iterations) = (stats.step, self.config().iterations);
        let event = StepEvent { step, iterations, view, gaussians, stats, memory };
        self.log.step(&event, self.t0.elapsed().as_secs_f64())?;
        self.events.push_back(RunEvent::Step(event));
        Ok(())
    }

    /// `error`, which stopped the run at step `step`, with what to do next.
    fn stopped_at(&self, error: anyhow::Error, step: u32) -> anyhow::Error {
        let context = self.stopped_context(&error, step);
        error.context(context)
    }

    fn stopped_context(&self, error: &anyhow::Error, step: u32) -> String {
        let out = &self.config().out;
        let out_of_memory =
            error.chain().any(|e| matches!(e.downcast_ref(), Some(GpuError::OutOfMemory { .. })));
        if !out.join(CHECKPOINT_FILE).is_file() {
            return format!(
                "training stopped at step {step}, before its first checkpoint (every {} steps): \
                 there is nothing to resume",
                self.checkpoint_every
            );
        }
        if out_of_memory {
            // A resumed run keeps its resolution and Gaussian cap: only the photos' share of
            // the GPU may change.
            let targets = self.trainer.targets();
            let mib = targets.budget().min(targets.counts().resident_bytes) >> 20;
            format!(
                "training stopped at step {step}; `trgs train --out {} --resume --target-memory \
                 M` with M below the {mib} MiB of photos held now continues from the last \
                 checkpoint, or start a new run with --downscale (or, with --densify mcmc, a \
                 lower --cap)",
                out.display()
            )
        } else {
            format!(
                "training stopped at step {step}; `trgs train --out {} --resume` continues from the \
                 last checkpoint",
                out.display()
            )
        }
    }
}
