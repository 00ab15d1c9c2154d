//! `propid report RUN.tsv`: the one file a person opens after a run — the fit, the diagnosis,
//! interactive zoomable plots, and the commands that reproduce it, in a single self-contained
//! HTML page (no network needed to view it).
//!
//! ```text
//!  RUN.tsv ─► science::fit::fit_path ─► fit table + fit figure
//!          ─► science::diagnose::diagnose ─► verdict text + diagnosis figure
//!          ─► html::page (uPlot embedded) ─► report.html
//! ```

use std::path::{Path, PathBuf};

use anyhow::Context;
use std::io::Write;

use propid_io::input::Mappable;
use propid_io::output::AtomicOutput;
use propid_science::diagnose::{diagnose, report_figure, to_text, Options};
use propid_science::fit::{figure, fit_path, FitError, FitOptions, FitReport};
use propid_science::result::{Air, Outcome};

use crate::html;

/// Arguments of `propid report`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The recording (propid's TSV, from `drive`, `sim`, `replay` or `import`).
    pub file: PathBuf,
    /// Where to write the page (default: the recording's name with `.html`).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// The propeller and air, for C_Q.
    #[command(flatten)]
    pub propeller: super::PropellerArgs,
    /// How the columns are read.
    #[command(flatten)]
    pub reading: super::ReadingArgs,
}

fn fit_rows(fit: &FitReport, options: &FitOptions) -> Vec<Vec<String>> {
    let mut rows = vec![
        vec![
            "J (inertia)".into(),
            format!("{:.6e}", fit.mass),
            format!("{:.2e}", fit.mass_stderr),
            "kg·m²".into(),
        ],
        vec![
            "c1 (viscous)".into(),
            format!("{:.6e}", fit.c1 + 0.0),
            format!("{:.2e}", fit.c1_stderr),
            "N·m·s/rad".into(),
        ],
        vec![
            "c2 (quadratic drag)".into(),
            format!("{:.6e}", fit.c2),
            format!("{:.2e}", fit.c2_stderr),
            "N·m·s²/rad²".into(),
        ],
        vec![
            "RMS of the acceleration residual".into(),
            format!("{:.4e}", fit.rms),
            String::new(),
            "rad/s²".into(),
        ],
        vec![
            "samples fitted (after the seed's trimming)".into(),
            fit.samples.to_string(),
            String::new(),
            format!("of {} rows", fit.rows),
        ],
        vec![
            "condition number".into(),
            format!("{:.3e}", fit.condition_number),
            String::new(),
            String::new(),
        ],
    ];
    if let Some(cq) = fit.c_q {
        rows.push(vec![
            "C_Q (torque coefficient)".into(),
            format!("{cq:.5e}"),
            String::new(),
            format!(
                "1 (Q = C_Q·ρ·n²·D⁵, n in rev/s; D = {} m, ρ = {} kg/m³)",
                options.diameter.unwrap_or(f64::NAN),
                options.density
            ),
        ]);
    }
    rows
}

/// Where the file has a stand's columns (thrust, voltage, current): what `propid propulsion`
/// says of it — C_T and C_Q over speed, the figure of merit, thrust per watt, the motor's
/// constants and its efficiency map — and its plot; without a diameter, what to give.
fn propulsion_sections(
    tsv: &Path,
    name: &str,
    options: &FitOptions,
) -> anyhow::Result<Vec<String>> {
    use propid_science::propulsion::{self as p, read};
    let (rec, _) = read::read_path(tsv, &read::ReadOptions::default())?;
    if rec.thrust.is_none() && rec.voltage.is_none() && rec.current.is_none() {
        return Ok(Vec::new());
    }
    let head = "<section><h2>Propulsion: thrust, torque, power and the motor</h2>\n";
    let Some(diameter) = options.diameter else {
        return Ok(vec![format!(
            "{head}<p>The file has a stand's columns (thrust, voltage or current): give <code>--diameter</code> (7in, 0.1778m) for C_T and C_Q over speed, the figure of merit, thrust per watt and the motor's efficiency map (<code>propid propulsion</code>).</p></section>\n"
        )]);
    };
    let identified = p::Air::with_density(options.density, None)
        .and_then(|air| p::identify(&rec, &p::Options::at(diameter, air)));
    Ok(match identified {
        Ok(result) => vec![
            format!(
                "{head}<p>As <code>propid propulsion {} --diameter {diameter:.4}m</code> gives it (with <code>--pole-pairs</code> for an electrical speed, <code>--command-is-duty</code> for an ESC's duty).</p>\n<pre>{}</pre></section>\n",
                html::escape(name),
                html::escape(&p::text::propulsion_text(&result, name))
            ),
            html::figure_section(&p::figure::figure(&result, Some(&rec)), "propulsion"),
        ],
        Err(why) => vec![format!(
            "{head}<p class=\"verdict\">cannot judge: {}</p></section>\n",
            html::escape(&why)
        )],
    })
}

/// Builds the report page for a recording. `reproduce` lists the commands that made the
/// recording (shown before the commands that make the report).
pub fn build(tsv: &Path, fit_options: &FitOptions, reproduce: &[String]) -> anyhow::Result<String> {
    build_from(&Mappable::new(tsv)?, fit_options, reproduce)
}

fn build_from(
    input: &Mappable,
    fit_options: &FitOptions,
    reproduce: &[String],
) -> anyhow::Result<String> {
    let name = input.name().to_string();
    let tsv = input.path();
    let mut sections = Vec::new();
    let (fit, fit_samples) =
        fit_path(tsv, fit_options, &mut |_, _| {}).map_err(|FitError::Input(e)| input.rename(e))?;
    let mut s = String::from("<section><h2>Fit: the seed's model, solved exactly</h2>\n");
    s += "<p>J·dω/dt = F − c1·ω − c2·ω·|ω|, with the seed's trimming (the last complete run of rows, \
          minus its first 10 %) and bounds.</p>\n";
    s += &html::table(
        &["parameter", "value", "± 1σ", "unit"],
        &fit_rows(&fit, fit_options),
    );
    for w in &fit.warnings {
        s += &format!("<p class=\"verdict\">warning: {}</p>\n", html::escape(w));
    }
    s += "</section>\n";
    sections.push(s);
    sections.push(html::figure_section(&figure(&fit, &fit_samples), "fit"));

    let super::DiagnosisInput {
        rows,
        skipped,
        notes,
        thrust,
    } = super::DiagnosisInput::read(tsv, &fit_options.reading, false)
        .map_err(|e| input.rename(e))?;
    let samples: Vec<_> = rows.into_iter().map(|row| row.sample).collect();
    let options = Options {
        reading: fit_options.reading,
        ..Options::default()
    };
    let air = fit_options.diameter.map(|diameter_m| Air {
        diameter_m,
        density_kg_m3: fit_options.density,
    });
    let mut outcome = Outcome::from_fit(&fit, fit_options.c1_max > 0.0, air);
    match diagnose(&samples, options) {
        Ok(report) => {
            if let Some(o) = Outcome::from_diagnosis(&report, skipped as u64, air) {
                outcome = o;
            }
            let text = to_text(&report, &name);
            let mut s = String::from(
                "<section><h2>Diagnosis: what the model gets wrong, and why</h2>\n<pre>",
            );
            s += &html::escape(&text);
            s += "</pre>\n";
            if skipped > 0 {
                s += &format!("<p>{skipped} rows with missing values were skipped.</p>\n");
            }
            for note in &notes {
                s += &format!("<p class=\"verdict\">warning: {}</p>\n", html::escape(note));
            }
            s += "</section>\n";
            sections.push(s);
            sections.push(html::figure_section(&report_figure(&report), "diagnose"));
        }
        Err(e) => sections.push(format!(
            "<section><h2>Diagnosis</h2><p class=\"verdict\">cannot judge: {}</p></section>\n",
            html::escape(&e.to_string())
        )),
    }
    if let Some(rec) = &thrust {
        outcome.add_thrust(rec);
    }

    sections.extend(propulsion_sections(tsv, &name, fit_options)?);

    // The headline: the Result (the extended model's where the diagnosis could judge).
    let mut head = String::from("<section><h2>Result</h2>\n<pre>");
    head += &html::escape(&outcome.to_text());
    head += "</pre>\n";
    for w in outcome
        .warnings
        .iter()
        .filter(|w| !fit.warnings.contains(w))
    {
        head += &format!("<p class=\"verdict\">warning: {}</p>\n", html::escape(w));
    }
    head += "</section>\n";
    sections.insert(0, head);

    let mut s = String::from("<section><h2>Reproduce</h2>\n<pre>");
    for c in reproduce {
        s += &html::escape(c);
        s.push('\n');
    }
    // In metres with its unit (a bare number is refused), without float noise.
    let diameter = fit_options
        .diameter
        .map(|d| {
            let m = format!("{d:.6}");
            format!(
                " --diameter {}m",
                m.trim_end_matches('0').trim_end_matches('.')
            )
        })
        .unwrap_or_default();
    s += &html::escape(&format!(
        "propid fit {name}{diameter}\npropid diagnose {name}{diameter}\npropid report {name}{diameter}\n"
    ));
    s += "</pre>\n<p>Made by propid ";
    s += env!("CARGO_PKG_VERSION");
    s += ". Plots: drag to zoom, double-click to reset.</p></section>\n";
    sections.push(s);
    Ok(html::page(&format!("propid report: {name}"), &sections))
}

/// Runs `propid report`. The page is written through an
/// [`AtomicOutput`](propid_io::output::AtomicOutput): never over the recording itself, and
/// whole or not at all.
pub fn run(args: Args) -> anyhow::Result<()> {
    let out = args
        .output
        .clone()
        .unwrap_or_else(|| args.file.with_extension("html"));
    let input = Mappable::new(&args.file)?;
    let mut page_file = AtomicOutput::create(&out, &[&args.file])?;
    let (diameter, density) = args.propeller.resolve()?;
    let options = FitOptions {
        diameter,
        density,
        reading: args.reading.reading(),
        ..FitOptions::default()
    };
    let page = build_from(&input, &options, &[])?;
    page_file
        .write_all(page.as_bytes())
        .and_then(|()| page_file.commit())
        .with_context(|| format!("writing {}", out.display()))?;
    eprintln!("report written to {}", out.display());
    Ok(())
}
