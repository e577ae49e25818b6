//! What a batch script run reports: one line per step (ok, error, pass,
//! fail, skipped), the files written, and the table `pinsight batch`
//! prints. Serialised as the `--json` report.

use serde::Serialize;

/// The outcome of one step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    Ok,
    Error,
    Pass,
    Fail,
}

impl Outcome {
    pub fn word(self) -> &'static str {
        match self {
            Outcome::Ok => "ok",
            Outcome::Error => "ERROR",
            Outcome::Pass => "pass",
            Outcome::Fail => "FAIL",
        }
    }
}

/// One step's report.
#[derive(Debug, Clone, Serialize)]
pub struct StepReport {
    pub index: usize,
    pub kind: String,
    /// What the step did (or the check's figure and threshold).
    pub what: String,
    pub outcome: Outcome,
    /// The value found (checks), or details / the error.
    pub detail: String,
}

/// The whole run.
#[derive(Debug, Clone, Serialize)]
pub struct BatchReport {
    pub script: String,
    pub steps: Vec<StepReport>,
    pub checks_passed: usize,
    pub checks_failed: usize,
    pub step_errors: usize,
    /// Stopped by Ctrl-C before the last step.
    pub interrupted: bool,
    /// Files the export steps wrote (each complete: crate::output).
    pub written: Vec<String>,
}

impl BatchReport {
    pub fn success(&self) -> bool {
        self.checks_failed == 0 && self.step_errors == 0 && !self.interrupted
    }

    /// The summary table printed at the end of a run.
    pub fn table(&self) -> String {
        let mut out = format!(
            "pinsight batch {} — {} steps\n",
            self.script,
            self.steps.len()
        );
        let what_w = self
            .steps
            .iter()
            .map(|s| s.what.chars().count())
            .max()
            .unwrap_or(4)
            .clamp(4, 60);
        out.push_str(&format!(
            "{:>3}  {:<7} {:<what_w$}  {:<6} {}\n",
            "#", "kind", "what", "result", "detail"
        ));
        for s in &self.steps {
            let what: String = if s.what.chars().count() > what_w {
                let mut t: String = s.what.chars().take(what_w - 1).collect();
                t.push('…');
                t
            } else {
                s.what.clone()
            };
            out.push_str(&format!(
                "{:>3}  {:<7} {:<what_w$}  {:<6} {}\n",
                s.index,
                s.kind,
                what,
                s.outcome.word(),
                s.detail
            ));
        }
        out.push_str(&format!(
            "checks: {} passed, {} failed; step errors: {} — {}\n",
            self.checks_passed,
            self.checks_failed,
            self.step_errors,
            if self.success() { "OK" } else { "FAILED" }
        ));
        if self.interrupted {
            out.push_str(&format!(
                "interrupted (Ctrl-C) after step {}: later steps did not run\n",
                self.steps.len()
            ));
        }
        if self.written.is_empty() {
            out.push_str("files written: none\n");
        } else {
            out.push_str(&format!("files written: {}\n", self.written.join(", ")));
        }
        out
    }
}
