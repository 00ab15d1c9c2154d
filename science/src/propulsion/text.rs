//! The identification and the sizing as text a propulsion engineer reads.

use std::fmt::Write;

use super::law::Coefficient;
use super::size::{Answer, Target};
use super::units::G0;
use super::{Propulsion, Quantity, TAU};

fn gf(newtons: f64) -> f64 {
    newtons / (G0 * 1e-3)
}

fn opt(v: Option<f64>, decimals: usize) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{x:.decimals$}"),
        _ => "–".into(),
    }
}

fn coefficient(out: &mut String, c: &Coefficient, p: &Propulsion) {
    let sym = c.kind.symbol();
    let what = match c.kind {
        super::Kind::Thrust => "thrust",
        super::Kind::Torque => "torque",
    };
    let n = c.reference_speed;
    let _ = writeln!(
        out,
        "  {sym} = {}  at {:.0} rpm (the power law {what} ∝ n^p, p = {}; {} {})",
        c.at_reference.describe(),
        n * 60.0,
        c.exponent.describe(),
        c.points,
        match c.method {
            super::Method::Plateaus => "steady plateaus",
            super::Method::Dynamic => "load-cell readings of a dynamic run",
        }
    );
    let _ = writeln!(
        out,
        "      quadratic law (one {sym} for all speeds): {}; sizing uses the {}",
        c.quadratic.describe(),
        if c.speed_dependent {
            "power law (p differs from 2 by more than 3 standard errors)"
        } else {
            "quadratic law"
        }
    );
    if let Some(lag) = &c.sensor_lag {
        let _ = writeln!(out, "      load-cell lag {}", lag.describe());
    }
    let _ = writeln!(out, "      {}", c.zero);
    if !c.bands.is_empty() {
        let _ = writeln!(
            out,
            "      {:>13}  {:>5}  {:>22}  {:>8}  {:>5}{}",
            "speed [rpm]",
            "pts",
            sym,
            "Re_D",
            "M_tip",
            if p.chord.is_some() { "   Re_0.75" } else { "" }
        );
        for b in &c.bands {
            let _ = writeln!(
                out,
                "      {:>6.0}–{:<6.0}  {:>5}  {:>22}  {:>8.2e}  {:>5.3}{}{}",
                b.from * 60.0,
                b.to * 60.0,
                b.plateaus,
                match &b.coefficient {
                    Quantity::CannotJudge { .. } => "–".to_string(),
                    q => super::quantity::plus_minus(
                        q.value().unwrap_or(f64::NAN),
                        q.stderr().unwrap_or(f64::NAN)
                    ),
                },
                b.reynolds,
                b.tip_mach,
                b.reynolds_075
                    .map_or(String::new(), |r| format!("  {r:>8.2e}")),
                if b.law_agrees {
                    ""
                } else {
                    "  (the power law misses this band)"
                }
            );
        }
    }
}

/// The identification as text. `file` names the recording.
pub fn propulsion_text(p: &Propulsion, file: &str) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "propid propulsion {file}: {} rows, {} steady plateaus; D = {:.4} m ({:.2} in); {}",
        p.rows,
        p.operating_points.len(),
        p.diameter,
        p.diameter / 0.0254,
        p.air.describe()
    );
    let _ = writeln!(
        out,
        "Conventions: T = C_T·ρ·n²·D⁴, Q = C_Q·ρ·n²·D⁵, n in rev/s; C_P = 2π·C_Q. A coefficient scales as 1/ρ."
    );
    for w in &p.warnings {
        let _ = writeln!(out, "WARNING: {w}");
    }
    let _ = writeln!(out, "\nPropeller:");
    for c in [&p.thrust, &p.torque].into_iter().flatten() {
        coefficient(&mut out, c, p);
    }
    if let Some(c2) = p.c2() {
        let _ = writeln!(out, "  the seed's c2 at that speed: {}", c2.describe());
    }
    if let Some(perf) = &p.performance {
        let n = perf.speed;
        let _ = writeln!(
            out,
            "  at {:.0} rpm (Re_D = {:.3e}, tip Mach {:.3}): C_P = {}, figure of merit {}, thrust per mechanical watt {} ({:.2} gf/W), T·D/Q = C_T/C_Q = {} (needs neither ρ nor the speed)",
            n * 60.0,
            p.air.reynolds_rotational(n, p.diameter),
            p.air.tip_mach(n, p.diameter),
            perf.c_p.describe(),
            perf.figure_of_merit.describe(),
            perf.thrust_per_watt.describe(),
            perf.thrust_per_watt.value().map_or(f64::NAN, gf),
            perf.thrust_torque_ratio.describe(),
        );
    }
    if !p.operating_points.is_empty() {
        let _ = writeln!(out, "\nSteady plateaus:");
        let _ = writeln!(
            out,
            "  {:>7} {:>8} {:>8} {:>8} {:>8} {:>6} {:>7} {:>6} {:>6} {:>5} {:>7} {:>5} {:>6} {:>6}",
            "rpm",
            "T [N]",
            "Q [N·m]",
            "C_T",
            "C_Q",
            "FM",
            "P [W]",
            "gf/W",
            "V",
            "I [A]",
            "P_e [W]",
            "duty",
            "η",
            "gf/W_e"
        );
        for o in &p.operating_points {
            let _ = writeln!(
                out,
                "  {:>7.0} {:>8} {:>8} {:>8} {:>8} {:>6} {:>7} {:>6} {:>6} {:>5} {:>7} {:>5} {:>6} {:>6}",
                o.rpm,
                opt(o.thrust, 3),
                opt(o.torque, 4),
                opt(o.c_t, 4),
                opt(o.c_q, 5),
                opt(o.figure_of_merit, 3),
                opt(o.mechanical_power, 1),
                opt(o.thrust_per_mechanical_watt.map(gf), 2),
                opt(o.voltage, 2),
                opt(o.current, 2),
                opt(o.electrical_power, 1),
                opt(o.duty, 3),
                opt(o.efficiency, 3),
                opt(o.thrust_per_electrical_watt.map(gf), 2),
            );
        }
    }
    let _ = writeln!(out, "\nMotor:");
    match (&p.motor, &p.motor_absent) {
        (Some(m), _) => {
            let same = |a: &Quantity, b: &Quantity| match (a, b) {
                (
                    Quantity::CannotJudge { reason: x, .. },
                    Quantity::CannotJudge { reason: y, .. },
                ) => x == y,
                _ => false,
            };
            if same(&m.kv, &m.resistance) {
                let _ = writeln!(out, "  Kv and R: {}", m.resistance.describe());
            } else {
                let _ = writeln!(
                    out,
                    "  Kv = {} (back-EMF: d·V_bus = K_e·ω + R·I_bus/d, {} points{})",
                    m.kv.describe(),
                    m.back_emf_points,
                    m.back_emf_rms
                        .map_or(String::new(), |r| format!(", residual {r:.3} V RMS"))
                );
                let _ = writeln!(
                    out,
                    "  R = {} (windings, wiring and switches)",
                    m.resistance.describe()
                );
            }
            if same(&m.kt, &m.no_load_current) {
                let _ = writeln!(out, "  K_t and I_0: {}", m.kt.describe());
            } else {
                let _ = writeln!(
                    out,
                    "  K_t = {} (shaft torque against motor current; in SI K_t = K_e)",
                    m.kt.describe()
                );
                let _ = writeln!(
                    out,
                    "  no-load current I_0 = {}",
                    m.no_load_current.describe()
                );
            }
            if let Some(f) = &m.current_filter {
                let _ = writeln!(out, "  the ESC's current filter: {}", f.describe());
            }
            match &m.losses {
                Some(l) => {
                    let _ = writeln!(
                        out,
                        "  losses: friction torque Q_f = {}, copper r = R/K_t² = {} ({})",
                        l.friction_torque.describe(),
                        l.copper.describe(),
                        l.source
                    );
                }
                None => {
                    let _ = writeln!(
                        out,
                        "  losses: not measured (no independent torque with voltage and current)"
                    );
                }
            }
        }
        (None, Some(why)) => {
            let _ = writeln!(out, "  {why}");
        }
        (None, None) => {}
    }
    out
}

fn target(t: &Target) -> String {
    match t {
        Target::Thrust(n) => format!("thrust {n:.3} N ({:.0} gf)", gf(*n)),
        Target::Torque(q) => format!("torque {q:.4} N·m"),
        Target::Speed(w) => format!("speed {:.0} rpm", w / TAU * 60.0),
    }
}

/// The sizing as text.
pub fn size_text(a: &Answer) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "propid size (ρ = {:.4} kg/m³):", a.density);
    for p in &a.points {
        let _ = writeln!(out, "\n{} per rotor:", target(&p.target));
        let _ = writeln!(
            out,
            "  speed   {:.0} ± {:.0} rpm ({:.1} rad/s)",
            p.rpm,
            p.speed.stderr / TAU * 60.0,
            p.speed.value
        );
        if let Some(t) = p.thrust {
            let _ = writeln!(
                out,
                "  thrust  {:.3} ± {:.3} N ({:.0} gf)",
                t.value,
                t.stderr,
                gf(t.value)
            );
        }
        let _ = writeln!(
            out,
            "  torque  {:.4} ± {:.4} N·m",
            p.torque.value, p.torque.stderr
        );
        let _ = writeln!(
            out,
            "  shaft power {:.1} ± {:.1} W{}{}",
            p.mechanical_power.value,
            p.mechanical_power.stderr,
            p.figure_of_merit
                .map_or(String::new(), |f| format!(", figure of merit {f:.3}")),
            p.thrust_per_watt
                .map_or(String::new(), |t| format!(", {:.2} gf/W", gf(t)))
        );
        if let Some(e) = &p.electrical {
            let _ = writeln!(out, "  electrical ({}):", e.from);
            if let (Some(i), Some(v)) = (e.motor_current, e.motor_voltage) {
                let _ = writeln!(out, "    motor current {i:.2} A at {v:.2} V");
            }
            let _ = writeln!(
                out,
                "    input power {:.1} W, efficiency {:.1} %, {:.2} gf/W",
                e.power,
                100.0 * e.efficiency,
                gf(e.thrust_per_watt)
            );
            if let Some(i) = e.dc_current {
                let _ = writeln!(
                    out,
                    "    DC link: {i:.2} A per controller{}{}",
                    e.duty
                        .map_or(String::new(), |d| format!(" at duty {:.1} %", 100.0 * d)),
                    e.ripple_current.map_or(String::new(), |r| format!(
                        ", capacitor ripple {r:.2} A rms"
                    ))
                );
            }
        }
        let t = &p.totals;
        if t.rotors > 1 || t.battery_current.is_some() {
            let _ = writeln!(
                out,
                "  vehicle of {}: thrust {:.2} N ({:.0} gf), shaft power {:.0} W{}{}{}{}",
                t.rotors,
                t.thrust,
                gf(t.thrust),
                t.mechanical_power,
                t.electrical_power
                    .map_or(String::new(), |p| format!(", electrical {p:.0} W")),
                t.battery_current
                    .map_or(String::new(), |i| format!(", battery {i:.1} A")),
                t.c_rate.map_or(String::new(), |c| format!(" ({c:.1} C)")),
                t.endurance_minutes
                    .map_or(String::new(), |m| format!(", {m:.1} min")),
            );
        }
        for n in &p.notes {
            let _ = writeln!(out, "  NOTE: {n}");
        }
    }
    for k in &a.kv_advice {
        let _ = writeln!(
            out,
            "\nWhich motor for {} at {:.2} V (duty ≤ {:.0} %, R = {:.4} Ω, I_0 = {:.2} A):",
            target(&k.target),
            k.voltage,
            100.0 * k.max_duty,
            k.resistance,
            k.no_load_current
        );
        match (k.kv_min, &k.why_not) {
            (Some(kv), _) => {
                let _ = writeln!(
                    out,
                    "  Kv ≥ {kv:.0} rpm/V; at that Kv the motor draws {:.2} A ({:.2} A from the DC link); a higher Kv reaches it with headroom and more current",
                    k.motor_current.unwrap_or(f64::NAN),
                    k.dc_current.unwrap_or(f64::NAN)
                );
            }
            (None, Some(why)) => {
                let _ = writeln!(out, "  no Kv: {why}");
            }
            (None, None) => {}
        }
    }
    out
}
