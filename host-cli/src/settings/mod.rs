//! Typed settings: every setting of a command knows its flag, its Cyphal register and its
//! environment variable; text from any of them becomes a checked value through the one parse the
//! setting defines; and every error is a value, rendered once in the words of where the text
//! came from.
//!
//! ```text
//!  flags (clap) ─────────────────────┐
//!  environment (UAVCAN__NODE__ID …) ──┼─► raw settings: Option<Given<S>> per setting S
//!  register file (uavcan.node.id: …) ─┘   (a flag wins over the environment, the environment
//!                                          over the file, the file over the default)
//!                                      │
//!                                      ▼ TryFrom (each S::parse; all errors collected)
//!                  checked settings (NodeId, SetpointPeriod, Schedule, Bus …) | ConfigErrors
//! ```
//! A setting is a type implementing [`Setting`] (its [`Names`] and its `parse`); a command's raw
//! settings are a struct of `Option<Given<S>>` fields that clap fills from the flags. The struct
//! lists its fields twice, each time destructured without `..`: in [`Fields::visit`] (where the
//! environment and the register file reach them) and in its `TryFrom` (where they are checked).
//! A field added to one and forgotten in the other does not compile. Errors are collected, not
//! returned at the first: a run with three settings missing says all three.

use std::collections::HashMap;
use std::fmt;
use std::marker::PhantomData;
use std::path::{Path, PathBuf};

use propid_core::can::IdError;
use propid_drive_host::register_file::{self, Entry};
use propid_drive_proto::settings::{RangeError, SetpointRangeError};
use propid_transport::{BitrateError, IfaceSpec, SpecError};

mod values;
pub use values::*;

/// A setting's three names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Names {
    /// The flag without its dashes (`node-id`); `None`: no flag.
    pub flag: Option<&'static str>,
    /// The Cyphal register (`uavcan.node.id`); `None`: not a register.
    pub register: Option<&'static str>,
    /// The environment variable (`UAVCAN__NODE__ID`); `None`: none.
    pub env: Option<&'static str>,
}

impl Names {
    /// A flag that is nothing else.
    pub const fn flag(flag: &'static str) -> Names {
        Names {
            flag: Some(flag),
            register: None,
            env: None,
        }
    }

    /// A register with its flag and environment variable.
    pub const fn register(flag: &'static str, register: &'static str, env: &'static str) -> Names {
        Names {
            flag: Some(flag),
            register: Some(register),
            env: Some(env),
        }
    }

    /// The names other than the one `origin` used, for the parenthesis after a message.
    fn others(&self, origin: Option<&Origin>) -> Vec<String> {
        let mut out = Vec::new();
        if let Some(f) = self.flag.filter(|_| !matches!(origin, Some(Origin::Flag))) {
            out.push(format!("flag --{f}"));
        }
        if let Some(r) = self
            .register
            .filter(|_| !matches!(origin, Some(Origin::File { .. })))
        {
            out.push(format!("register {r}"));
        }
        if let Some(e) = self
            .env
            .filter(|_| !matches!(origin, Some(Origin::Environment)))
        {
            out.push(format!("environment variable {e}"));
        }
        out
    }
}

/// Where a setting's text came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Origin {
    /// Its flag.
    Flag,
    /// Its environment variable.
    Environment,
    /// A register file's line.
    File {
        /// The file.
        path: PathBuf,
        /// The line, from 1.
        line: usize,
    },
}

/// Text given for setting `S`, and where it came from.
pub struct Given<S> {
    /// The text.
    pub text: String,
    /// Where from.
    pub origin: Origin,
    setting: PhantomData<fn() -> S>,
}

impl<S> Given<S> {
    /// `text` from `origin`.
    pub fn new(text: impl Into<String>, origin: Origin) -> Self {
        Given {
            text: text.into(),
            origin,
            setting: PhantomData,
        }
    }
}

impl<S> Clone for Given<S> {
    fn clone(&self) -> Self {
        Given::new(self.text.clone(), self.origin.clone())
    }
}

impl<S> fmt::Debug for Given<S> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:?} from {:?}", self.text, self.origin)
    }
}

impl<S> std::str::FromStr for Given<S> {
    type Err = std::convert::Infallible;

    /// A flag's text (clap parses flags with this; the setting checks it later, with the rest).
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        Ok(Given::new(text, Origin::Flag))
    }
}

/// One setting: its names and how text becomes its checked value.
pub trait Setting: 'static {
    /// The checked value.
    type Value;
    /// Its flag, register and environment variable.
    const NAMES: Names;
    /// What the help says it is (the names are added).
    const HELP: &'static str;
    /// The value `text` gives, or what is wrong with it.
    fn parse(text: &str) -> Result<Self::Value, Problem>;
}

/// Defines settings, each a unit type with its value type, its names, its help and its parse:
/// `Name: Value = names, "help", parse;` or, for a number of a range type,
/// `Name: Value = names, "help", within RangeType;`.
macro_rules! setting {
    () => {};
    (
        $(#[$doc:meta])* $name:ident: $value:ty = $names:expr, $help:literal, within $range:ident;
        $($rest:tt)*
    ) => {
        $crate::settings::setting! {
            $(#[$doc])* $name: $value = $names, $help,
                |text: &str| $crate::settings::number(text, $range::new);
        }
        $crate::settings::setting! { $($rest)* }
    };
    (
        $(#[$doc:meta])* $name:ident: $value:ty = $names:expr, $help:literal, $parse:expr;
        $($rest:tt)*
    ) => {
        $(#[$doc])*
        pub struct $name;

        impl $crate::settings::Setting for $name {
            type Value = $value;
            const NAMES: $crate::settings::Names = $names;
            const HELP: &'static str = $help;
            fn parse(text: &str) -> Result<$value, $crate::settings::Problem> {
                ($parse)(text)
            }
        }

        $crate::settings::setting! { $($rest)* }
    };
}
pub(crate) use setting;

/// Defines a command's clap arguments with its settings: each setting one line (`field:
/// SettingType as "VALUE"`), register-only settings (no flag), nested argument groups that hold
/// settings (the bus), then any other clap fields as written. Generates the struct and its
/// [`Fields`] (so the environment and a register file reach every setting it lists).
macro_rules! command_args {
    (
        $(#[$attr:meta])*
        pub struct $name:ident {
            settings { $( $field:ident: $setting:ty as $value_name:literal, )* }
            registers { $( $reg:ident: $reg_setting:ty, )* }
            nested { $( $nested:ident: $nested_ty:ty, )* }
            $( $(#[$other_attr:meta])* pub $other:ident: $other_ty:ty, )*
        }
    ) => {
        $(#[$attr])*
        #[derive(clap::Args, Debug, Clone)]
        pub struct $name {
            $(
                #[doc = concat!("The setting [`", stringify!($setting), "`].")]
                #[arg(
                    long = $crate::settings::flag::<$setting>(),
                    help = $crate::settings::help::<$setting>(),
                    value_name = $value_name
                )]
                pub $field: Option<$crate::settings::Given<$setting>>,
            )*
            $(
                #[doc = concat!("The setting [`", stringify!($reg_setting), "`] (no flag).")]
                #[arg(skip)]
                pub $reg: Option<$crate::settings::Given<$reg_setting>>,
            )*
            $(
                #[doc = concat!("Settings of [`", stringify!($nested_ty), "`].")]
                #[command(flatten)]
                pub $nested: $nested_ty,
            )*
            $( $(#[$other_attr])* pub $other: $other_ty, )*
        }

        impl $crate::settings::Fields for $name {
            fn visit(
                &mut self,
                f: &mut dyn FnMut($crate::settings::Names, &mut dyn $crate::settings::Slot),
            ) {
                $( $crate::settings::field(f, &mut self.$field); )*
                $( $crate::settings::field(f, &mut self.$reg); )*
                $( $crate::settings::Fields::visit(&mut self.$nested, f); )*
            }
        }
    };
}
pub(crate) use command_args;

/// `checked!(errors; a, b, …)`: each of the `Option`s `a`, `b`, … (a setting's checked value, or
/// `None` when its error was recorded in `errors`) as its value, or `return Err(errors)` when
/// any is missing or anything else was recorded.
macro_rules! checked {
    ($errors:ident; $($v:ident),+ $(,)?) => {
        let ($(Some($v),)+) = ($($v,)+) else {
            return Err($errors);
        };
        $errors.check()?;
    };
}
pub(crate) use checked;

/// The flag of `S`, for clap's `long = …`.
pub const fn flag<S: Setting>() -> &'static str {
    match S::NAMES.flag {
        Some(f) => f,
        None => panic!("a setting without a flag has no clap argument"),
    }
}

/// The help of `S`: what it is, then its register and environment variable.
pub fn help<S: Setting>() -> String {
    let names = S::NAMES;
    match (names.register, names.env) {
        (Some(r), Some(e)) => format!("{} (register {r}, {e})", S::HELP),
        (None, Some(e)) => format!("{} ({e})", S::HELP),
        _ => S::HELP.to_string(),
    }
}

/// What is wrong with a setting's value. Each knows only the value; [`SettingError`] names the
/// setting.
#[derive(Clone, Debug, PartialEq)]
pub enum Problem {
    /// Required and not given.
    Missing,
    /// Given as 65535, the register's "unset", where a value is required.
    Unset,
    /// An ID out of range or not a number.
    Id(IdError),
    /// A number out of its range.
    Range(RangeError),
    /// A setpoint range that is not −1 ≤ lo < hi ≤ 1.
    SetpointRange(SetpointRangeError),
    /// Text that is not the register's type (`real64[2]`, …).
    Type {
        /// The text given.
        text: String,
        /// The type it must be.
        ty: &'static str,
    },
    /// An MTU other than 8 or 64.
    Mtu(String),
    /// An interface that is not `socketcan:IFACE` or `slcan:DEVICE[@BAUD]`.
    Iface {
        /// The text given.
        text: String,
        /// What is wrong with it.
        error: SpecError,
    },
    /// A bit rate that is not one or two integers.
    Bitrate(BitrateError),
    /// A value that does not go with another setting's (the sentence says which).
    Conflict(String),
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Problem::Missing => write!(f, "is not set"),
            Problem::Unset => write!(f, "65535 leaves it unset, and it is needed"),
            Problem::Id(e) => write!(f, "{e}"),
            Problem::Range(e) => write!(f, "{e}"),
            Problem::SetpointRange(e) => write!(f, "{e}"),
            Problem::Type { text, ty } => write!(f, "`{text}` is not a valid {ty}"),
            Problem::Mtu(text) => {
                write!(f, "`{text}` is not 8 (Classic CAN) or 64 (CAN FD)")
            }
            Problem::Iface { text, error } => write!(
                f,
                "interface `{text}`: {error} (expected {})",
                IfaceSpec::SYNTAX
            ),
            Problem::Bitrate(e) => write!(f, "{e}"),
            Problem::Conflict(why) => write!(f, "{why}"),
        }
    }
}

/// One setting's error: which setting (its names), where its text came from (`None`: not
/// given), what is wrong.
#[derive(Clone, Debug, PartialEq)]
pub struct SettingError {
    /// The setting.
    pub names: Names,
    /// Where the text came from.
    pub origin: Option<Origin>,
    /// What is wrong.
    pub problem: Problem,
}

impl fmt::Display for SettingError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = &self.names;
        let first = |names: [Option<String>; 3]| names.into_iter().flatten().next();
        let lead = match &self.origin {
            Some(Origin::Flag) => n.flag.map(|x| format!("--{x}")),
            Some(Origin::Environment) => n.env.map(|e| format!("environment variable {e}")),
            Some(Origin::File { path, line }) => n
                .register
                .map(|r| format!("{}:{line}: register {r}", path.display())),
            None => None,
        }
        .or_else(|| {
            first([
                n.flag.map(|x| format!("--{x}")),
                n.register.map(|r| format!("register {r}")),
                n.env.map(|e| format!("environment variable {e}")),
            ])
        })
        .unwrap_or_default();
        if self.problem == Problem::Missing {
            // Not given anywhere: say every way to give it.
            let mut ways = Vec::new();
            if let Some(r) = n.register {
                ways.push(format!("register {r} in a --registers file"));
            }
            if let Some(e) = n.env {
                ways.push(format!("environment variable {e}"));
            }
            write!(f, "{lead} is not set")?;
            if !ways.is_empty() && n.flag.is_some() {
                write!(f, " (nor its {})", ways.join(", nor its "))?;
            }
            return Ok(());
        }
        write!(f, "{lead}: {}", self.problem)?;
        let others = n.others(self.origin.as_ref());
        let others: Vec<&String> = others.iter().filter(|o| **o != lead).collect();
        if !others.is_empty() {
            let list: Vec<&str> = others.iter().map(|s| s.as_str()).collect();
            write!(f, " ({})", list.join(", "))?;
        }
        Ok(())
    }
}

/// One thing wrong with a command's configuration.
#[derive(Clone, Debug, PartialEq)]
pub enum ConfigError {
    /// A setting.
    Setting(SettingError),
    /// A register file that cannot be read.
    Unreadable {
        /// The file.
        path: PathBuf,
        /// The operating system's words.
        why: String,
    },
    /// A register file line that is not `name: value`.
    Line {
        /// The file.
        path: PathBuf,
        /// The line's error.
        error: register_file::LineError,
    },
    /// A register file line naming a register the command does not have (or cannot write).
    UnknownRegister {
        /// The file.
        path: PathBuf,
        /// The line, from 1.
        line: usize,
        /// The name.
        name: String,
        /// It exists but is read-only.
        read_only: bool,
    },
    /// A flag that is not a setting (a pattern file, `--set NAME=VALUE`) whose value cannot
    /// be used.
    Flag {
        /// The flag, without its dashes.
        flag: &'static str,
        /// What is wrong.
        why: String,
    },
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ConfigError::Setting(e) => write!(f, "{e}"),
            ConfigError::Unreadable { path, why } => {
                write!(f, "cannot read the register file {}: {why}", path.display())
            }
            ConfigError::Line { path, error } => {
                write!(f, "{}:{}: {error}", path.display(), error.line)
            }
            ConfigError::UnknownRegister {
                path,
                line,
                name,
                read_only,
            } => {
                let what = if *read_only {
                    "is read-only"
                } else {
                    "is not a register of this command"
                };
                write!(f, "{}:{line}: {name} {what}", path.display())
            }
            ConfigError::Flag { flag, why } => write!(f, "--{flag} {why}"),
        }
    }
}

/// Everything wrong with one command's configuration, one line each (exit status 2).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ConfigErrors(pub Vec<ConfigError>);

impl fmt::Display for ConfigErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0.as_slice() {
            [one] => write!(f, "{one}"),
            all => {
                write!(f, "{} settings are wrong:", all.len())?;
                for e in all {
                    write!(f, "\n  {e}")?;
                }
                Ok(())
            }
        }
    }
}

impl std::error::Error for ConfigErrors {}

impl ConfigErrors {
    /// True when nothing is wrong.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// Adds one error.
    pub fn push(&mut self, e: ConfigError) {
        self.0.push(e);
    }

    /// Adds a setting's error.
    pub fn setting(&mut self, names: Names, origin: Option<Origin>, problem: Problem) {
        self.push(ConfigError::Setting(SettingError {
            names,
            origin,
            problem,
        }));
    }

    /// `Err(self)` when anything is wrong.
    pub fn check(self) -> Result<(), ConfigErrors> {
        if self.is_empty() {
            Ok(())
        } else {
            Err(self)
        }
    }

    /// The value given for `S` (`Some(None)`: not given; `None`: wrong, recorded).
    pub fn given<S: Setting>(&mut self, raw: Option<Given<S>>) -> Option<Option<S::Value>> {
        match raw {
            None => Some(None),
            Some(g) => match S::parse(&g.text) {
                Ok(v) => Some(Some(v)),
                Err(problem) => {
                    self.setting(S::NAMES, Some(g.origin), problem);
                    None
                }
            },
        }
    }

    /// The value given for `S`, or `default`.
    pub fn or<S: Setting>(&mut self, raw: Option<Given<S>>, default: S::Value) -> Option<S::Value> {
        self.given(raw).map(|v| v.unwrap_or(default))
    }

    /// The value given for `S`; its absence is an error.
    pub fn required<S: Setting>(&mut self, raw: Option<Given<S>>) -> Option<S::Value> {
        self.present::<S, S::Value>(raw.map(|g| Given::new(g.text, g.origin)), Some)
    }

    /// The value given for an `S` whose value may say "unset" (an ID register at 65535); its
    /// absence or "unset" is an error.
    pub fn required_id<S, T>(&mut self, raw: Option<Given<S>>) -> Option<T>
    where
        S: Setting<Value = Option<T>>,
    {
        self.present::<S, T>(raw, |v| v)
    }

    /// The value given for an `S` whose value may say "unset", or `default` when not given;
    /// "unset" is an error.
    pub fn id_or<S, T>(&mut self, raw: Option<Given<S>>, default: T) -> Option<T>
    where
        S: Setting<Value = Option<T>>,
    {
        match raw {
            None => Some(default),
            given => self.required_id(given),
        }
    }

    fn present<S: Setting, T>(
        &mut self,
        raw: Option<Given<S>>,
        get: impl FnOnce(S::Value) -> Option<T>,
    ) -> Option<T> {
        let origin = raw.as_ref().map(|g| g.origin.clone());
        match self.given(raw)? {
            Some(v) => match get(v) {
                Some(t) => Some(t),
                None => {
                    self.setting(S::NAMES, origin, Problem::Unset);
                    None
                }
            },
            None => {
                self.setting(S::NAMES, None, Problem::Missing);
                None
            }
        }
    }
}

/// A raw setting's slot, as [`Fields::visit`] hands it over.
pub trait Slot {
    /// Whether text was given already (by a flag, or by an earlier source).
    fn is_set(&self) -> bool;
    /// Gives it text.
    fn set(&mut self, text: &str, origin: Origin);
}

impl<S> Slot for Option<Given<S>> {
    fn is_set(&self) -> bool {
        self.is_some()
    }

    fn set(&mut self, text: &str, origin: Origin) {
        *self = Some(Given::new(text, origin));
    }
}

/// A command's raw settings: each field's names and slot, in order.
pub trait Fields {
    /// Hands every setting's names and slot to `f`.
    fn visit(&mut self, f: &mut dyn FnMut(Names, &mut dyn Slot));
}

/// Hands one field to a visitor (the setting's names come from its type).
pub fn field<S: Setting>(f: &mut dyn FnMut(Names, &mut dyn Slot), slot: &mut Option<Given<S>>) {
    f(S::NAMES, slot)
}

/// A register file, read.
pub struct RegisterFile {
    /// Where it is.
    pub path: PathBuf,
    /// Its `name: value` lines.
    pub entries: Vec<Entry>,
}

impl RegisterFile {
    /// Reads `path`; what cannot be read or is not `name: value` is recorded in `errors`.
    pub fn read(path: &Path, errors: &mut ConfigErrors) -> Option<RegisterFile> {
        let text = match std::fs::read_to_string(path) {
            Ok(t) => t,
            Err(e) => {
                errors.push(ConfigError::Unreadable {
                    path: path.to_path_buf(),
                    why: crate::os_words(&e),
                });
                return None;
            }
        };
        let (entries, bad) = register_file::read_entries(&text);
        for error in bad {
            errors.push(ConfigError::Line {
                path: path.to_path_buf(),
                error,
            });
        }
        Some(RegisterFile {
            path: path.to_path_buf(),
            entries,
        })
    }
}

/// Fills the slots no flag set: from the environment (`vars`) first, then from the register
/// file. A file line naming no setting's register is an error (`read_only`: the registers the
/// command serves but does not take from a file).
pub fn fill(
    raw: &mut dyn Fields,
    vars: &HashMap<String, String>,
    file: Option<&RegisterFile>,
    read_only: &[&str],
    errors: &mut ConfigErrors,
) {
    let mut registers = Vec::new();
    raw.visit(&mut |names, slot| {
        if let Some(r) = names.register {
            registers.push(r);
        }
        if slot.is_set() {
            return;
        }
        if let Some(text) = names.env.and_then(|e| vars.get(e)) {
            slot.set(text, Origin::Environment);
            return;
        }
        let entry = file.and_then(|f| {
            let r = names.register?;
            let e = f.entries.iter().rev().find(|e| e.name == r)?;
            Some((f, e))
        });
        if let Some((f, e)) = entry {
            slot.set(
                &e.value,
                Origin::File {
                    path: f.path.clone(),
                    line: e.line,
                },
            );
        }
    });
    let Some(file) = file else { return };
    for e in &file.entries {
        if !registers.contains(&e.name.as_str()) {
            errors.push(ConfigError::UnknownRegister {
                path: file.path.clone(),
                line: e.line,
                name: e.name.clone(),
                read_only: read_only.contains(&e.name.as_str()),
            });
        }
    }
}

/// The process's environment, as [`fill`] takes it.
pub fn environment() -> HashMap<String, String> {
    std::env::vars().collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use propid_core::can::NodeId;
    use propid_drive_proto::settings::Range;

    struct Period;
    impl Setting for Period {
        type Value = f64;
        const NAMES: Names = Names::register("period", "period", "PERIOD");
        const HELP: &'static str = "the period [s]";
        fn parse(text: &str) -> Result<f64, Problem> {
            seconds_in(
                text,
                Range {
                    lo: 0.0,
                    lo_open: true,
                    hi: 10.0,
                    hi_open: false,
                    unit: "s",
                },
            )
        }
    }

    struct Id;
    impl Setting for Id {
        type Value = Option<NodeId>;
        const NAMES: Names = Names::register("node-id", "uavcan.node.id", "UAVCAN__NODE__ID");
        const HELP: &'static str = "this node's ID";
        fn parse(text: &str) -> Result<Option<NodeId>, Problem> {
            node_id(text)
        }
    }

    #[derive(Default)]
    struct Raw {
        period: Option<Given<Period>>,
        id: Option<Given<Id>>,
    }

    impl Fields for Raw {
        fn visit(&mut self, f: &mut dyn FnMut(Names, &mut dyn Slot)) {
            let Raw { period, id } = self;
            field(f, period);
            field(f, id);
        }
    }

    fn file(lines: &[(usize, &str, &str)]) -> RegisterFile {
        RegisterFile {
            path: "x.reg".into(),
            entries: lines
                .iter()
                .map(|(line, name, value)| Entry {
                    line: *line,
                    name: name.to_string(),
                    value: value.to_string(),
                })
                .collect(),
        }
    }

    #[test]
    fn a_flag_wins_over_the_environment_which_wins_over_the_file() {
        let f = file(&[(1, "period", "3"), (2, "uavcan.node.id", "10")]);
        let vars = HashMap::from([("PERIOD".to_string(), "2.5".to_string())]);
        let mut raw = Raw::default();
        let mut errors = ConfigErrors::default();
        fill(&mut raw, &vars, Some(&f), &[], &mut errors);
        assert!(errors.is_empty());
        assert_eq!(raw.period.as_ref().unwrap().text, "2.5");
        assert_eq!(raw.period.as_ref().unwrap().origin, Origin::Environment);
        let id = raw.id.clone().unwrap();
        assert_eq!(
            (id.text.as_str(), id.origin),
            (
                "10",
                Origin::File {
                    path: "x.reg".into(),
                    line: 2
                }
            )
        );
        let mut raw = Raw {
            period: Some("4".parse().unwrap()),
            id: None,
        };
        fill(&mut raw, &vars, Some(&f), &[], &mut errors);
        assert_eq!(raw.period.unwrap().origin, Origin::Flag);
    }

    #[test]
    fn every_error_is_said_once_in_the_words_of_its_origin() {
        let mut e = ConfigErrors::default();
        let f = Origin::File {
            path: "x.reg".into(),
            line: 3,
        };
        assert_eq!(e.given(Some(Given::<Period>::new("fast", f))), None);
        assert_eq!(
            e.given(Some(Given::<Period>::new("0", Origin::Environment))),
            None
        );
        assert_eq!(
            e.given(Some(Given::<Period>::new("11", Origin::Flag))),
            None
        );
        assert_eq!(e.required_id::<Id, NodeId>(None), None);
        let unset = Some(Given::<Id>::new("65535", Origin::Environment));
        assert_eq!(e.required_id::<Id, NodeId>(unset), None);
        assert_eq!(e.or::<Period>(None, 2.0), Some(2.0));
        let lines: Vec<String> = e.0.iter().map(|x| x.to_string()).collect();
        assert_eq!(
            lines,
            [
                "x.reg:3: register period: `fast` is not a valid real64[1] (flag --period, environment variable PERIOD)",
                "environment variable PERIOD: must be a finite number above 0 and at most 10 s (got 0) (flag --period, register period)",
                "--period: must be a finite number above 0 and at most 10 s (got 11) (register period, environment variable PERIOD)",
                "--node-id is not set (nor its register uavcan.node.id in a --registers file, nor its environment variable UAVCAN__NODE__ID)",
                "environment variable UAVCAN__NODE__ID: 65535 leaves it unset, and it is needed (flag --node-id, register uavcan.node.id)",
            ]
        );
        assert!(e
            .to_string()
            .starts_with("5 settings are wrong:\n  x.reg:3"));
    }

    #[test]
    fn file_lines_that_name_no_setting_are_errors() {
        let f = file(&[(1, "no_such", "1"), (2, "uavcan.pub.x.type", "y")]);
        let mut errors = ConfigErrors::default();
        fill(
            &mut Raw::default(),
            &HashMap::new(),
            Some(&f),
            &["uavcan.pub.x.type"],
            &mut errors,
        );
        let lines: Vec<String> = errors.0.iter().map(|x| x.to_string()).collect();
        assert_eq!(
            lines,
            [
                "x.reg:1: no_such is not a register of this command",
                "x.reg:2: uavcan.pub.x.type is read-only"
            ]
        );
    }
}
