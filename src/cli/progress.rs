//! The league's progress as bars on a terminal: one per seat for `run`, one
//! for an exploit's best response. Where stderr is not a terminal the bars
//! draw nothing and the lines are printed plainly.

use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use league::run::view::{BudgetUnit, SeatProgress, View};
use std::io::Write;
use std::sync::Mutex;

#[derive(Default)]
pub struct Bars {
    multi: MultiProgress,
    seats: Mutex<Vec<(String, ProgressBar)>>,
    best_response: Mutex<Option<ProgressBar>>,
}

/// The bars' one look: `=> ` filling a bar of the template's width.
pub(crate) fn style(template: &str) -> ProgressStyle {
    ProgressStyle::with_template(template)
        .expect("a valid progress template")
        .progress_chars("=> ")
}

impl View for Bars {
    fn say(&self, line: &str) {
        if self.multi.is_hidden() {
            // Not eprintln!: a redirected stderr on a full disk would panic
            // the manager, the one process left to say what happened.
            let _ = writeln!(std::io::stderr(), "{line}");
        } else {
            self.multi.println(line).ok();
        }
    }

    fn seats(&self, names: &[String], env_steps: u64) {
        let mut seats = self.seats.lock().unwrap_or_else(|e| e.into_inner());
        for name in names {
            let bar = self.multi.add(ProgressBar::new(env_steps));
            bar.set_style(style(
                "{prefix:>12} [{bar:25}] {human_pos}/{human_len} steps {msg}",
            ));
            bar.set_prefix(name.clone());
            seats.push((name.clone(), bar));
        }
    }

    fn seat(&self, name: &str, p: &SeatProgress) {
        let seats = self.seats.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, bar)) = seats.iter().find(|(n, _)| n == name) {
            bar.set_position(p.env_steps);
            bar.set_message(format!(
                "| {:.0} steps/s | {} | {} matches",
                p.steps_per_s, p.state, p.matches
            ));
        }
    }

    fn best_response(&self, total: u64, unit: BudgetUnit) {
        let template = match unit {
            BudgetUnit::EnvSteps => {
                "best response [{elapsed_precise}] [{bar:25}] {human_pos}/{human_len} env steps"
            }
            BudgetUnit::Seconds => {
                "best response [{elapsed_precise}] [{bar:25}] {pos}/{len} s of training"
            }
        };
        let bar = self.multi.add(ProgressBar::new(total));
        bar.set_style(style(template));
        *self.best_response.lock().unwrap_or_else(|e| e.into_inner()) = Some(bar);
    }

    fn best_response_at(&self, done: u64) {
        if let Some(bar) = &*self.best_response.lock().unwrap_or_else(|e| e.into_inner()) {
            bar.set_position(done);
        }
    }

    fn finish(&self) {
        for (_, bar) in &*self.seats.lock().unwrap_or_else(|e| e.into_inner()) {
            bar.finish();
        }
        if let Some(bar) = self
            .best_response
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .take()
        {
            bar.finish_and_clear();
        }
    }
}
