//! Arguments shared by commands: mechanism parameters, how a rig log is
//! read, standard output.

use crate::model::params::{PARAM_SPECS, Params};
use anyhow::{Context, bail};
use std::io::Write;
use std::path::PathBuf;

/// Standard output for the commands' reports. A closed pipe (`pinsight …
/// | head`) is the reader's choice, not an error: from then on the text is
/// dropped and the command goes on (and finishes writing its files). Any
/// other write error is returned.
pub struct Stdout {
    inner: std::io::StdoutLock<'static>,
    closed: bool,
}

/// The locked standard output, tolerant of a closed pipe.
pub fn stdout() -> Stdout {
    Stdout {
        inner: std::io::stdout().lock(),
        closed: false,
    }
}

impl Write for Stdout {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.closed {
            return Ok(buf.len());
        }
        match self.inner.write(buf) {
            Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {
                self.closed = true;
                Ok(buf.len())
            }
            r => r,
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        if self.closed {
            return Ok(());
        }
        match self.inner.flush() {
            Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {
                self.closed = true;
                Ok(())
            }
            r => r,
        }
    }
}

/// Writes text to [`stdout`].
pub fn out(text: &str) -> anyhow::Result<()> {
    let mut o = stdout();
    o.write_all(text.as_bytes())
        .and_then(|()| o.flush())
        .map_err(|e| anyhow::Error::new(e).context("writing to standard output"))
}

/// `println!` through [`out`]: evaluates to `anyhow::Result<()>`.
macro_rules! outln {
    ($($t:tt)*) => {
        $crate::cli::common::out(&format!("{}\n", format_args!($($t)*)))
    };
}
/// `print!` through [`out`].
macro_rules! outp {
    ($($t:tt)*) => {
        $crate::cli::common::out(&format!($($t)*))
    };
}
pub(crate) use {outln, outp};

/// `--preset`, `--params FILE`, `--set key=value` (in that order of precedence,
/// lowest first).
#[derive(Debug, Clone, clap::Args, Default)]
pub struct ParamArgs {
    /// Base parameter set: paper (a representative pin-insertion head) or flores (the literature benchmark).
    #[arg(long)]
    pub preset: Option<String>,
    /// A TOML parameter file (flat keys as listed by `--set help`; may name its own `preset`).
    #[arg(long, value_name = "FILE")]
    pub params: Option<PathBuf>,
    /// Override one parameter, e.g. `--set clearance_mm=0.3` (repeatable; `--set help` lists the keys).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
}

impl ParamArgs {
    /// The parameters: preset, then file, then overrides; validated.
    pub fn resolve(&self) -> anyhow::Result<Params> {
        if self.sets.iter().any(|s| s == "help" || s == "?") {
            return Err(HelpShown(key_listing()).into());
        }
        let mut p = match &self.params {
            Some(path) => {
                let text = crate::input::read_text(path)
                    .with_context(|| format!("reading parameter file {}", path.display()))?;
                let table: toml::Table = text
                    .parse()
                    .map_err(|e| anyhow::anyhow!("parameter file {}: {e}", path.display()))?;
                if let (Some(cli), Some(toml::Value::String(file))) =
                    (&self.preset, table.get("preset"))
                    && cli != file
                {
                    bail!(
                        "--preset {cli} conflicts with preset = \"{file}\" in {}",
                        path.display()
                    );
                }
                let mut text_with_base = text.clone();
                if table.get("preset").is_none()
                    && let Some(preset) = &self.preset
                {
                    text_with_base = format!("preset = \"{preset}\"\n{text}");
                }
                Params::from_toml_str(&text_with_base)
                    .map_err(|e| anyhow::anyhow!("parameter file {}: {e}", path.display()))?
            }
            None => Params::preset(self.preset.as_deref().unwrap_or("paper"))?,
        };
        p.apply_overrides(&self.sets)?;
        Ok(p)
    }
}

/// A listing the user asked for (`--set help`): printed on stdout with exit
/// status 0 by `main`, not an error.
#[derive(Debug)]
pub struct HelpShown(pub String);

impl std::fmt::Display for HelpShown {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for HelpShown {}

/// Every parameter key with its meaning and range.
pub fn key_listing() -> String {
    let mut out = String::from("parameter keys (use --set key=value or a TOML file):\n");
    let p = Params::paper();
    for s in PARAM_SPECS {
        let v = p.get(s.key).map(|v| v.to_string()).unwrap_or_default();
        out.push_str(&format!(
            "  {:<28} {} [{}] (paper: {})\n",
            s.key, s.help, s.range, v
        ));
    }
    out
}

/// Parses "A..B" (either end optional) into a range of f64 or u64 values.
pub fn parse_list_f64(s: &str, what: &str) -> anyhow::Result<Vec<f64>> {
    s.split(',')
        .filter(|x| !x.trim().is_empty())
        .map(|x| {
            x.trim()
                .parse::<f64>()
                .map_err(|_| anyhow::anyhow!("{what}: `{x}` is not a number"))
        })
        .collect()
}

/// Option values bounded by what they mean. Each parser refuses a value
/// outside its range with the range named, so no option can ask for
/// gigabytes (`--points 100000000`) or silently become something else
/// (`--revs 0`). Numbers are read as decimal (no hex).
pub mod bounds {
    use crate::fmt::fmt_num;

    fn number(s: &str, what: &str) -> Result<f64, String> {
        let t = s.trim();
        if t.is_empty() {
            return Err(format!("{what}: empty value"));
        }
        let x: f64 = t
            .parse()
            .map_err(|_| format!("{what}: `{t}` is not a decimal number"))?;
        if !x.is_finite() {
            return Err(format!("{what}: `{t}` is not a finite number"));
        }
        Ok(x)
    }

    fn in_range(s: &str, what: &str, lo: f64, hi: f64, lo_open: bool) -> Result<f64, String> {
        let x = number(s, what)?;
        let ok = if lo_open { x > lo } else { x >= lo } && x <= hi;
        if ok {
            Ok(x)
        } else {
            Err(format!(
                "{what}: {} is outside the allowed range {}{} … {}",
                fmt_num(x),
                if lo_open { "above " } else { "" },
                fmt_num(lo),
                fmt_num(hi)
            ))
        }
    }

    fn count(s: &str, what: &str, lo: usize, hi: usize) -> Result<usize, String> {
        let x = number(s, what)?;
        if x.fract() != 0.0 {
            return Err(format!("{what}: {} is not a whole number", fmt_num(x)));
        }
        if x < lo as f64 || x > hi as f64 {
            return Err(format!(
                "{what}: {} is outside the allowed range {lo} … {hi}",
                fmt_num(x)
            ));
        }
        Ok(x as usize)
    }

    /// A clearance limit of the wear trend, mm: above 0 … 10.
    pub fn clearance_limit_mm(s: &str) -> Result<f64, String> {
        in_range(s, "clearance limit (mm)", 0.0, 10.0, true)
    }
    /// A depth tolerance ± of the wear trend's derived limit, mm: above 0 … 10.
    pub fn depth_tolerance_mm(s: &str) -> Result<f64, String> {
        in_range(s, "depth tolerance (mm)", 0.0, 10.0, true)
    }
    /// The level of a forecast interval: 0.5 … 0.99.
    pub fn forecast_level(s: &str) -> Result<f64, String> {
        in_range(s, "forecast interval level", 0.5, 0.99, false)
    }
    /// Crank-angle grid points per revolution: 8 (45°) … 7200 (0.05°).
    pub fn points(s: &str) -> Result<usize, String> {
        count(s, "points per revolution", 8, 7200)
    }
    /// Predicted revolutions of an overlay ensemble.
    pub fn overlay_revs(s: &str) -> Result<usize, String> {
        count(s, "predicted revolutions", 2, 10_000)
    }
    /// Simulated revolutions of a calibration (per clearance).
    pub fn calibrate_revs(s: &str) -> Result<usize, String> {
        count(s, "simulated revolutions", 8, 10_000)
    }
    /// Reported revolutions of a simulation (fractional): at least a
    /// thousandth (0.36° of crank), below which no figure is defined.
    pub fn revs(s: &str) -> Result<f64, String> {
        in_range(s, "revolutions", 1e-3, 10_000.0, false)
    }
    /// Warm-up revolutions (fractional, 0 allowed).
    pub fn warmup(s: &str) -> Result<f64, String> {
        in_range(s, "warm-up revolutions", 0.0, 10_000.0, false)
    }
    /// Relative tolerance of an adaptive integrator.
    pub fn rtol(s: &str) -> Result<f64, String> {
        in_range(s, "relative tolerance", 1e-14, 0.1, false)
    }
    /// Absolute tolerance (SI).
    pub fn atol(s: &str) -> Result<f64, String> {
        in_range(s, "absolute tolerance", 0.0, 1e-3, false)
    }
    /// A fixed step in seconds.
    pub fn step_s(s: &str) -> Result<f64, String> {
        in_range(s, "step (s)", 1e-12, 0.1, false)
    }
    /// Ensemble realisations.
    pub fn ensemble(s: &str) -> Result<usize, String> {
        count(s, "realisations", 1, 10_000)
    }
    /// Crank-angle spacing of an output grid in degrees.
    pub fn grid_deg(s: &str) -> Result<f64, String> {
        in_range(s, "grid spacing (°)", 0.01, 90.0, false)
    }
    /// A resolution (mm or N) of a scene.
    pub fn resolution(s: &str) -> Result<f64, String> {
        in_range(s, "resolution", 0.0, 1e6, true)
    }
    /// A sensor lag in µs.
    pub fn lag_us(s: &str) -> Result<f64, String> {
        in_range(s, "sensor lag (µs)", 0.0, 100_000.0, false)
    }
    /// A relative spread (0.01 = 1 %).
    pub fn fraction(s: &str) -> Result<f64, String> {
        in_range(s, "relative spread", 0.0, 1.0, false)
    }
    /// Magnification of drawn offsets.
    pub fn magnify(s: &str) -> Result<f64, String> {
        in_range(s, "magnification", 1.0, 1000.0, false)
    }
    /// Worker threads.
    pub fn jobs(s: &str) -> Result<usize, String> {
        count(s, "worker threads", 1, 1024)
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        #[test]
        fn sizes_are_bounded_and_messages_name_the_range() {
            assert_eq!(points("720"), Ok(720));
            for bad in [
                "0",
                "7",
                "10000000",
                "100000000",
                "1e300",
                "-5",
                "0x10",
                "",
                "nan",
                "2.5",
            ] {
                let e = points(bad).unwrap_err();
                assert!(e.starts_with("points per revolution"), "{bad}: {e}");
            }
            assert!(points("100000000").unwrap_err().contains("8 … 7200"));
            assert!(overlay_revs("0").unwrap_err().contains("2 … 10000"));
            assert!(revs("0").is_err());
            assert_eq!(revs("0.5"), Ok(0.5));
            assert_eq!(warmup("0"), Ok(0.0));
            let e = rtol("1e-300").unwrap_err();
            assert!(e.contains("1e-300") && e.len() < 120, "{e}");
            assert!(step_s("inf").unwrap_err().contains("not a finite number"));
            assert_eq!(jobs("2"), Ok(2));
        }
    }
}

/// How a rig log is read: a channel map for a rig that names its topics
/// differently, and `rig` metadata overrides (`log`, `overlay`,
/// `calibrate`).
#[derive(Debug, Clone, clap::Args)]
pub struct LogReadArgs {
    /// Channel map (TOML: a map file, or a session file with a [channels] table).
    #[arg(long, value_name = "MAP.toml")]
    pub channels: Option<PathBuf>,
    /// Override a `rig` metadata key, e.g. --meta laser_zero_mm=10.0 (repeatable).
    #[arg(long = "meta", value_name = "KEY=VALUE")]
    pub meta: Vec<String>,
}

impl LogReadArgs {
    /// The engine's load options: the channel map read, `--meta` KEY=VALUE
    /// pairs split (one without `=` is an error naming it).
    pub fn load_options(&self) -> anyhow::Result<crate::rig::LoadOptions> {
        let mut opts = crate::rig::LoadOptions::default();
        if let Some(p) = &self.channels {
            opts.channel_map = crate::rig::ChannelMap::from_file(p)?;
        }
        for kv in &self.meta {
            let (k, v) = kv
                .split_once('=')
                .with_context(|| format!("--meta '{kv}': expected KEY=VALUE"))?;
            opts.meta_overrides
                .insert(k.trim().to_string(), v.trim().to_string());
        }
        Ok(opts)
    }
}

/// The integrator and its tolerances (`simulate`, `sweep`).
#[derive(Debug, Clone, clap::Args)]
pub struct SolverArgs {
    /// Integrator: rk4, dopri5, dop853 or radau5.
    #[arg(long, default_value = "dop853")]
    pub method: String,
    /// Relative tolerance (adaptive methods).
    #[arg(long, default_value_t = 1e-8, value_parser = bounds::rtol)]
    pub rtol: f64,
    /// Absolute tolerance, SI (m, m/s).
    #[arg(long, default_value_t = 1e-14, value_parser = bounds::atol)]
    pub atol: f64,
}

impl SolverArgs {
    /// The method named by `--method`, or an error listing the allowed names.
    pub fn method(&self) -> anyhow::Result<crate::solver::Method> {
        crate::solver::Method::parse(&self.method).with_context(|| {
            format!(
                "invalid --method `{}` (allowed: rk4, dopri5, dop853, radau5)",
                self.method
            )
        })
    }
}

/// The logs `calibrate` and `overlay` run, and which shard of them.
#[derive(Debug, clap::Args)]
pub struct LogBatchArgs {
    /// The rig log (MCAP); several logs or folders of them run one after the other.
    #[arg(value_name = "LOG.mcap", required = true)]
    pub logs: Vec<PathBuf>,
    /// Run only shard K of N (K from 0) of the sorted logs; default from the
    /// cluster's environment (docs/scale.md).
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
}

impl LogBatchArgs {
    /// The shard (given or from the cluster's environment) and, when the
    /// whole run is one log file, that log (its report printed as is, not
    /// as a batch of one).
    pub fn resolve(
        &self,
    ) -> anyhow::Result<(crate::plant::shard::Shard, Option<&std::path::Path>)> {
        let shard = crate::plant::shard::Shard::resolve(self.shard.as_deref())
            .map_err(anyhow::Error::msg)?;
        let single = match self.logs.as_slice() {
            [log] if shard.is_whole() && !log.is_dir() => Some(log.as_path()),
            _ => None,
        };
        Ok((shard, single))
    }
}

/// The logs of one shard (`calibrate` and `overlay` over several logs),
/// each run by `one`, which returns its report and the text to print: a
/// missing log or a failed run is listed as an error and the others go on.
/// With `json` one array of `{file, report}` / `{file, error}` is printed at
/// the end. Exit status 3 when any log failed.
pub fn run_log_batch<R: serde::Serialize>(
    shard: crate::plant::shard::Shard,
    inputs: &[PathBuf],
    json: bool,
    mut one: impl FnMut(&crate::plant::log_batch::BatchLog) -> anyhow::Result<(R, String)>,
) -> anyhow::Result<std::process::ExitCode> {
    let logs = crate::plant::log_batch::log_batch(shard, inputs);
    if !shard.is_whole() {
        eprintln!("shard {shard}: {} log(s)", logs.len());
    }
    let mut failed = 0;
    let mut reports = Vec::new();
    for l in &logs {
        let r = match &l.missing {
            Some(why) => Err(anyhow::anyhow!("{}: {why}", l.path.display())),
            None => one(l),
        };
        match r {
            Ok((report, text)) => {
                if !json {
                    outp!("{text}")?;
                }
                reports.push(serde_json::json!({"file": l.path, "report": report}));
            }
            Err(e) => {
                failed += 1;
                let e = crate::cli::error_text(&e);
                eprintln!("error: {e}");
                reports.push(serde_json::json!({"file": l.path, "error": e}));
            }
        }
    }
    if json {
        outln!("{}", serde_json::to_string_pretty(&reports)?)?;
    }
    Ok(if failed > 0 {
        std::process::ExitCode::from(3)
    } else {
        std::process::ExitCode::SUCCESS
    })
}
