//! One module per subcommand: its clap arguments and the `run` that calls the libraries.

pub mod demo;
pub mod diagnose;
pub mod drive;
pub mod fit;
pub mod import;
pub mod plan;
pub mod propulsion;
pub mod replay;
pub mod report;
pub mod sim;
pub mod sim_drive;
pub mod size;
pub mod stand_instruments;
pub mod telega;

/// How the recording's columns are read, for every command that fits (`fit`, `diagnose`,
/// `report`): the answers to the plausibility gate's findings.
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct ReadingArgs {
    /// The force column's sign is reversed (the torque works against the acceleration it
    /// causes): read it negated.
    #[arg(long)]
    pub flip_torque: bool,
    /// The velocity column's unit: rad/s (propid's), rpm, rev/s or deg/s; it is converted to
    /// rad/s before anything is fitted (the acceleration stays in rad/s²).
    #[arg(long, value_parser = propid_science::plausibility::SpeedUnit::parse, default_value = "rad/s")]
    pub velocity_unit: propid_science::plausibility::SpeedUnit,
}

impl ReadingArgs {
    /// The reading these flags ask for.
    pub fn reading(&self) -> propid_science::plausibility::Reading {
        propid_science::plausibility::Reading {
            flip_torque: self.flip_torque,
            velocity_unit: self.velocity_unit,
        }
    }
}

/// Air density when none is given [kg/m³].
pub const DENSITY: f64 = propid_science::propulsion::air::ISA_DENSITY;

/// The propeller and the air, for C_Q (`fit`, `diagnose`, `report`).
#[derive(clap::Args, Debug)]
pub struct PropellerArgs {
    /// Propeller diameter, for the torque coefficient C_Q: 7in, 0.1778m, 178mm (a bare number is
    /// metres, and refused outside 0.02–3 m).
    #[arg(long, allow_negative_numbers = true, value_parser = propulsion::quantity(propid_science::propulsion::units::Dimension::Length))]
    pub diameter: Option<propid_science::propulsion::units::Parsed>,
    /// The air for C_Q (default: ISA sea level, 1.225 kg/m³).
    #[command(flatten)]
    pub air: propulsion::AirArgs,
}

impl PropellerArgs {
    /// The diameter [m] and density [kg/m³], checked: a bare diameter outside 0.02–3 m is
    /// refused (7 is inches far more often than a 7 m rotor).
    pub fn resolve(&self) -> Result<(Option<f64>, f64), propid_io::InputError> {
        use propid_science::propulsion::{air::Air, units::Dimension};
        // One default everywhere: 1.225 kg/m³ (ISA sea level, as every propeller table quotes it).
        let sea_level = Air::with_density(DENSITY, None).map_err(propid_io::InputError::invalid)?;
        let density = self.air.air(sea_level)?.density;
        if let Some(d) = &self.diameter {
            if let Some(note) =
                propulsion::unit_notes("--diameter", d, Dimension::Length, 0.02..=3.0)
            {
                return Err(propid_io::InputError::invalid(note));
            }
        }
        Ok((self.diameter.map(|d| d.si), density))
    }

    /// The Result's propeller, when a diameter was given.
    pub fn air(&self) -> Result<Option<propid_science::result::Air>, propid_io::InputError> {
        let (diameter, density) = self.resolve()?;
        Ok(diameter.map(|diameter_m| propid_science::result::Air {
            diameter_m,
            density_kg_m3: density,
        }))
    }
}

/// What `diagnose` and `report` read: the rows the diagnosis uses (every value of the sample
/// finite), and the recording a Result's C_T rests on where the file has a thrust column.
pub struct DiagnosisInput {
    /// Rows with t, force, velocity and acceleration all finite.
    pub rows: Vec<propid_io::tsv::Row>,
    /// Rows read but left out (a missing value).
    pub skipped: usize,
    /// What the reader noticed (a cut last line, repeated times).
    pub notes: Vec<String>,
    /// Time, speed and thrust ([`propid_science::propulsion::read::thrust_of_rows`]).
    pub thrust: Option<propid_science::propulsion::Recording>,
}

impl DiagnosisInput {
    /// Reads `path`. A stand's thrust cell updates on rows of its own (the torque's are others):
    /// rows with a stand measurement are read for C_T, which then rests on the rows
    /// `propid propulsion` reads, and left out of the diagnosis like any row with a missing
    /// value.
    ///
    /// Velocity glitches (a sample that jumps away from both neighbours and straight back) are
    /// announced in the notes, and left out when `despike`.
    pub fn read(
        path: &std::path::Path,
        reading: &propid_science::plausibility::Reading,
        despike: bool,
    ) -> Result<DiagnosisInput, propid_io::InputError> {
        let table = propid_io::tsv::read_rows(path, DiagnosisInput::keep)?;
        let notes = table.notes();
        Ok(DiagnosisInput::from_rows(
            &table.name,
            table.rows,
            table.skipped,
            &table.stand_columns,
            notes,
            reading,
            despike,
        ))
    }

    /// The rows [`DiagnosisInput::read`] keeps of a file: those with a complete sample, or a
    /// stand measurement.
    pub fn keep(row: &propid_io::tsv::Row) -> bool {
        row.sample.is_finite() || row.stand != propid_io::tsv::Stand::NONE
    }

    /// [`DiagnosisInput::read`] of rows already read (those [`DiagnosisInput::keep`] keeps, of
    /// a file `name` with the stand columns `columns`; `skipped` others; `notes` the reader's).
    pub fn from_rows(
        name: &str,
        mut rows: Vec<propid_io::tsv::Row>,
        skipped: usize,
        columns: &[propid_io::tsv::StandColumn],
        mut notes: Vec<String>,
        reading: &propid_science::plausibility::Reading,
        despike: bool,
    ) -> DiagnosisInput {
        let thrust = propid_science::propulsion::read::thrust_of_rows(&rows, columns, reading);
        let read = rows.len();
        rows.retain(|row| row.sample.is_finite());
        notes.extend(propid_io::import::tsv_glitches(name, &mut rows, despike));
        DiagnosisInput {
            skipped: skipped + read - rows.len(),
            rows,
            notes,
            thrust,
        }
    }
}

/// A speed flag's value: rad/s, or rpm with `rpm` (`12000rpm`), as every speed flag takes it.
pub fn speed(text: &str) -> Result<f64, String> {
    propid_drive_proto::settings::parse_speed(text)
        .ok_or_else(|| format!("`{text}` is not a speed: give rad/s (1256.6) or rpm (12000rpm)"))
}
