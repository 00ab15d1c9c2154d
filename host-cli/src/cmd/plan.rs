//! `propid plan`: design the excitation from a prior, around [`propid_science::plan::design`].

use std::path::PathBuf;

use anyhow::Context;
use propid_science::plan::{design, to_file, Constraints, Plan, Prior};

use crate::cmd::drive::LoHi;
use crate::settings::{command_args, environment, fill, ConfigErrors};
use crate::InputError;
use propid_drive_proto::settings::SetpointRange;

command_args! {
    /// Arguments of `propid plan`.
    pub struct Args {
        settings {
            setpoint_rat_lo_hi: LoHi as "LO HI",
        }
        registers {}
        nested {}
        /// A fit from an earlier run (`propid fit` YAML): its mass and c2 are the prior.
        #[arg(long)]
        pub fit: Option<PathBuf>,
        /// Prior inertia J [kg·m²] (instead of --fit).
        #[arg(long)]
        pub inertia: Option<f64>,
        /// Prior drag c2 [N·m·s²/rad²] (instead of --fit).
        #[arg(long)]
        pub c2: Option<f64>,
        /// The drive's torque at setpoint 1 [N·m].
        #[arg(long)]
        pub max_torque: f64,
        /// Largest speed the stand may reach: rad/s, or rpm (`12000rpm`), as `drive --max-speed`.
        #[arg(long, value_name = "SPEED", value_parser = super::speed)]
        pub max_speed: Option<f64>,
        /// Longest pattern [s] (the seed's pattern_duration).
        #[arg(long, default_value_t = 200.0)]
        pub duration: f64,
        /// Plan for this relative standard error of J and c2 [%] instead of the seed's precision.
        #[arg(long)]
        pub target_stderr: Option<f64>,
        /// Feedback rate [Hz] of the drive.
        #[arg(long, default_value_t = 500.0)]
        pub rate: f64,
        /// Where to write the pattern file (for `drive --pattern-file` and `sim --pattern-file`).
        #[arg(short, long, default_value = "plan.json")]
        pub output: PathBuf,
    }
}

/// A `key: number` line of a YAML file.
fn yaml_number(text: &str, key: &str, file: &str) -> Result<f64, InputError> {
    text.lines()
        .enumerate()
        .find_map(|(i, l)| {
            let (k, v) = l.split_once(':')?;
            (k.trim() == key).then(|| (i, v.split('#').next().unwrap_or("").trim().to_string()))
        })
        .ok_or_else(|| {
            InputError::invalid(format!("{file}: no `{key}:` line (is it a propid fit?)"))
        })
        .and_then(|(i, v)| {
            v.parse().map_err(|_| {
                InputError::invalid(format!(
                    "{file}: line {}: `{key}: {v}` is not a number",
                    i + 1
                ))
            })
        })
}

impl Args {
    fn prior(&self) -> Result<Prior, InputError> {
        let (inertia, c2) = match (&self.fit, self.inertia, self.c2) {
            (Some(path), None, None) => {
                let name = path.display().to_string();
                let text = std::fs::read_to_string(path)
                    .map_err(|e| InputError::invalid(format!("{name}: cannot read: {e}")))?;
                (
                    yaml_number(&text, "mass", &name)?,
                    yaml_number(&text, "c2", &name)?,
                )
            }
            (None, Some(j), Some(c2)) => (j, c2),
            _ => {
                return Err(InputError::invalid(
                    "give the prior either as --fit FIT.yaml or as --inertia and --c2".into(),
                ))
            }
        };
        let mut prior = Prior::new(inertia, c2, self.max_torque);
        prior.rate = self.rate;
        prior.check()?;
        Ok(prior)
    }
}

fn print(plan: &Plan) {
    let e = &plan.excitation;
    eprintln!(
        "plan: {} with period {} s between {} and {} for {} s (after {} s at hi)",
        e.pattern, e.period, e.lo, e.hi, e.duration, e.init_duration
    );
    eprintln!(
        "plan: predicted relative standard error J {:.3} %, c2 {:.3} % (the seed's sine for as long: J {:.3} %, c2 {:.3} %)",
        100.0 * plan.predicted.rel_stderr_j,
        100.0 * plan.predicted.rel_stderr_c2,
        100.0 * plan.seed_sine.rel_stderr_j,
        100.0 * plan.seed_sine.rel_stderr_c2
    );
    eprintln!(
        "plan: matches the precision of the seed's {} s sine run in {:.0} s",
        plan.constraints.max_duration, plan.seconds_to_match_seed
    );
    for (label, seps) in [
        ("plan", &plan.separations),
        ("seed sine", &plan.seed_separations),
    ] {
        for s in seps {
            eprintln!(
                "{label}: {} vs {}: {} (regressor correlation {:.2})",
                s.effects.0,
                s.effects.1,
                if s.separable {
                    "separable"
                } else {
                    "NOT separable"
                },
                s.correlation
            );
        }
    }
}

/// Runs `propid plan`.
pub fn run(mut args: Args) -> anyhow::Result<()> {
    // The setpoint range is the drive's setting: from the flag or SETPOINT_RAT_LO_HI.
    let mut errors = ConfigErrors::default();
    fill(&mut args, &environment(), None, &[], &mut errors);
    let range = errors.or(args.setpoint_rat_lo_hi.take(), SetpointRange::SEED);
    let (Some(range), Ok(())) = (range, errors.clone().check()) else {
        return Err(errors.into());
    };
    let (lo, hi) = (range.lo(), range.hi());
    let prior = args.prior()?;
    if let Some(t) = args.target_stderr.filter(|t| !(*t > 0.0 && *t < 100.0)) {
        return Err(InputError::invalid(format!(
            "--target-stderr must be in (0, 100) % (got {t})"
        ))
        .into());
    }
    let constraints = Constraints {
        lo,
        hi,
        max_speed: args.max_speed,
        max_duration: args.duration,
    };
    let plan = design(&prior, &constraints, args.target_stderr.map(|p| p / 100.0))?;
    print(&plan);
    // Written whole, and never over the fit it was designed from.
    let inputs: Vec<&std::path::Path> = args.fit.iter().map(|p| p.as_path()).collect();
    let mut out = propid_io::output::AtomicOutput::create(&args.output, &inputs)?;
    std::io::Write::write_all(&mut out, to_file(&plan).as_bytes())
        .and_then(|()| out.commit())
        .with_context(|| format!("cannot write {}", args.output.display()))?;
    eprintln!("plan: written to {}", args.output.display());
    Ok(())
}
