//! The FMU's variables: one table that both the get/set functions and the
//! generated `modelDescription.xml` read. Names and value references are the
//! public interface; value references are unique across all types.

use crate::physics::params::{Params, MAX_BLOCKS, RANGES};
use crate::physics::solver::SolverKind;

/// What a variable is. Each variant is the FMU variable of the same name
/// (see [`Id::name`]); indexed variants carry the block / interface number 1..=8.
#[allow(missing_docs)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Id {
    // Real parameters
    Mp,
    Tp,
    Zeta,
    G,
    RecordScale,
    MaxStep,
    FrictionEps,
    Alpha(usize),
    Mus(usize),
    Muk(usize),
    // Real inputs
    Ag,
    Fext,
    // Real outputs
    Up,
    Vp,
    ApAbs,
    BaseShear,
    PeakUp,
    PeakApAbs,
    Einput,
    Ekinetic,
    Estrain,
    Eviscous,
    Efriction,
    TSwitch,
    Ub(usize),
    Vb(usize),
    Slip(usize),
    AbAbs(usize),
    F(usize),
    PeakSlip(usize),
    // Integers
    NBlocks,
    Solver,
    NEvents,
    NAmbiguous,
    // Booleans
    Stuck(usize),
    // Strings
    RecordFile,
}

/// FMI base type.
#[allow(missing_docs)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Real,
    Integer,
    Boolean,
    String,
}

/// FMI causality of a variable.
#[allow(missing_docs)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Causality {
    Parameter,
    Input,
    Output,
}

/// Array entries j = 1..=8 of block/interface quantities.
const ARRAY: u32 = 10;

impl Id {
    /// The value reference.
    pub fn vr(self) -> u32 {
        let at = |base: u32, j: usize| base + j as u32;
        match self {
            Id::Mp => 1,
            Id::Tp => 2,
            Id::Zeta => 3,
            Id::G => 4,
            Id::RecordScale => 5,
            Id::MaxStep => 6,
            Id::FrictionEps => 7,
            Id::Alpha(j) => at(10, j),
            Id::Mus(j) => at(20, j),
            Id::Muk(j) => at(30, j),
            Id::Ag => 100,
            Id::Fext => 101,
            Id::Up => 200,
            Id::Vp => 201,
            Id::ApAbs => 202,
            Id::BaseShear => 203,
            Id::PeakUp => 204,
            Id::PeakApAbs => 205,
            Id::Einput => 206,
            Id::Ekinetic => 207,
            Id::Estrain => 208,
            Id::Eviscous => 209,
            Id::Efriction => 210,
            Id::TSwitch => 211,
            Id::Ub(j) => at(300, j),
            Id::Vb(j) => at(310, j),
            Id::Slip(j) => at(320, j),
            Id::AbAbs(j) => at(330, j),
            Id::F(j) => at(340, j),
            Id::PeakSlip(j) => at(350, j),
            Id::NBlocks => 400,
            Id::Solver => 401,
            Id::NEvents => 402,
            Id::NAmbiguous => 403,
            Id::Stuck(j) => at(500, j),
            Id::RecordFile => 600,
        }
    }

    /// The variable with value reference `vr`, if any.
    pub fn from_vr(vr: u32) -> Option<Id> {
        let j = (vr % ARRAY) as usize;
        let in_array = (1..=MAX_BLOCKS).contains(&j);
        let array = |make: fn(usize) -> Id| in_array.then(|| make(j));
        match vr {
            1 => Some(Id::Mp),
            2 => Some(Id::Tp),
            3 => Some(Id::Zeta),
            4 => Some(Id::G),
            5 => Some(Id::RecordScale),
            6 => Some(Id::MaxStep),
            7 => Some(Id::FrictionEps),
            10..=19 => array(Id::Alpha),
            20..=29 => array(Id::Mus),
            30..=39 => array(Id::Muk),
            100 => Some(Id::Ag),
            101 => Some(Id::Fext),
            200 => Some(Id::Up),
            201 => Some(Id::Vp),
            202 => Some(Id::ApAbs),
            203 => Some(Id::BaseShear),
            204 => Some(Id::PeakUp),
            205 => Some(Id::PeakApAbs),
            206 => Some(Id::Einput),
            207 => Some(Id::Ekinetic),
            208 => Some(Id::Estrain),
            209 => Some(Id::Eviscous),
            210 => Some(Id::Efriction),
            211 => Some(Id::TSwitch),
            300..=309 => array(Id::Ub),
            310..=319 => array(Id::Vb),
            320..=329 => array(Id::Slip),
            330..=339 => array(Id::AbAbs),
            340..=349 => array(Id::F),
            350..=359 => array(Id::PeakSlip),
            400 => Some(Id::NBlocks),
            401 => Some(Id::Solver),
            402 => Some(Id::NEvents),
            403 => Some(Id::NAmbiguous),
            500..=509 => array(Id::Stuck),
            600 => Some(Id::RecordFile),
            _ => None,
        }
    }

    /// The public (structured) name, e.g. `alpha[2]`.
    pub fn name(self) -> String {
        let indexed = |base: &str, j: usize| format!("{base}[{j}]");
        match self {
            Id::Mp => "mp".into(),
            Id::Tp => "Tp".into(),
            Id::Zeta => "zeta".into(),
            Id::G => "g".into(),
            Id::RecordScale => "recordScale".into(),
            Id::MaxStep => "maxStep".into(),
            Id::FrictionEps => "frictionEps".into(),
            Id::Alpha(j) => indexed("alpha", j),
            Id::Mus(j) => indexed("mus", j),
            Id::Muk(j) => indexed("muk", j),
            Id::Ag => "ag".into(),
            Id::Fext => "Fext".into(),
            Id::Up => "up".into(),
            Id::Vp => "vp".into(),
            Id::ApAbs => "apAbs".into(),
            Id::BaseShear => "baseShear".into(),
            Id::PeakUp => "peakUp".into(),
            Id::PeakApAbs => "peakApAbs".into(),
            Id::Einput => "Einput".into(),
            Id::Ekinetic => "Ekinetic".into(),
            Id::Estrain => "Estrain".into(),
            Id::Eviscous => "Eviscous".into(),
            Id::Efriction => "Efriction".into(),
            Id::TSwitch => "tSwitch".into(),
            Id::Ub(j) => indexed("ub", j),
            Id::Vb(j) => indexed("vb", j),
            Id::Slip(j) => indexed("slip", j),
            Id::AbAbs(j) => indexed("abAbs", j),
            Id::F(j) => indexed("F", j),
            Id::PeakSlip(j) => indexed("peakSlip", j),
            Id::NBlocks => "nBlocks".into(),
            Id::Solver => "solver".into(),
            Id::NEvents => "nEvents".into(),
            Id::NAmbiguous => "nAmbiguous".into(),
            Id::Stuck(j) => indexed("stuck", j),
            Id::RecordFile => "recordFile".into(),
        }
    }

    /// The FMI base type.
    pub fn kind(self) -> Kind {
        match self {
            Id::NBlocks | Id::Solver | Id::NEvents | Id::NAmbiguous => Kind::Integer,
            Id::Stuck(_) => Kind::Boolean,
            Id::RecordFile => Kind::String,
            _ => Kind::Real,
        }
    }

    /// Parameter, input or output.
    pub fn causality(self) -> Causality {
        match self {
            Id::Mp
            | Id::Tp
            | Id::Zeta
            | Id::G
            | Id::RecordScale
            | Id::MaxStep
            | Id::FrictionEps
            | Id::Alpha(_)
            | Id::Mus(_)
            | Id::Muk(_)
            | Id::NBlocks
            | Id::Solver
            | Id::RecordFile => Causality::Parameter,
            Id::Ag | Id::Fext => Causality::Input,
            _ => Causality::Output,
        }
    }

    /// The inputs this output depends on at the same instant (direct
    /// feedthrough), from the equations (docs/coupling-ports.md). `Fext`
    /// acts on the structure's load at once: absolute accelerations, stick
    /// forces and the peak of |apAbs| see it, and a jump of it can break a
    /// stick (stick flags, and the forces and accelerations of any block).
    /// Nothing sees `ag`: it moves the support, and friction, the spring and
    /// the damper act on relative motion, so no absolute acceleration or force
    /// depends on it at the same instant. The rest is state only.
    pub fn input_dependencies(self) -> &'static [Id] {
        match self {
            Id::ApAbs | Id::PeakApAbs | Id::AbAbs(_) | Id::F(_) | Id::Stuck(_) => &[Id::Fext],
            _ => &[],
        }
    }

    /// The block / interface number of an indexed variable.
    pub fn block(self) -> Option<usize> {
        match self {
            Id::Alpha(j)
            | Id::Mus(j)
            | Id::Muk(j)
            | Id::Ub(j)
            | Id::Vb(j)
            | Id::Slip(j)
            | Id::AbAbs(j)
            | Id::F(j)
            | Id::PeakSlip(j)
            | Id::Stuck(j) => Some(j),
            _ => None,
        }
    }

    /// The range the FMU enforces on a parameter or input, as the model
    /// description's `min` and `max` (both included): from the table the
    /// checks use ([`RANGES`], [`crate::physics::params::MIN_MAX_STEP`], [`MAX_BLOCKS`], the solver
    /// codes). An end the check excludes (`zeta < 1`) is the closest value
    /// inside. `None` for outputs and strings.
    pub fn range(self) -> Option<(f64, Option<f64>)> {
        match self {
            Id::NBlocks => return Some((0.0, Some(MAX_BLOCKS as f64))),
            Id::Solver => {
                let codes = || (1..10).filter(|&c| SolverKind::from_code(c).is_some());
                let (lo, hi) = (codes().min()?, codes().max()?);
                return Some((lo as f64, Some(hi as f64)));
            }
            // 0 (automatic) or at least MIN_MAX_STEP: min is 0.
            Id::MaxStep => return Some((0.0, None)),
            _ if self.kind() != Kind::Real || self.causality() == Causality::Output => return None,
            _ => {}
        }
        let name = self.name();
        let base = name.split('[').next().unwrap_or(&name);
        let &(_, lo, hi, _) = RANGES.iter().find(|r| r.0 == base)?;
        // check_scalar excludes zeta = 1 (critical damping).
        let hi = if base == "zeta" {
            f64::from_bits(hi.to_bits() - 1)
        } else {
            hi
        };
        Some((lo, Some(hi)))
    }

    /// Whether the variable varies continuously in time (Real inputs and
    /// Real outputs but `tSwitch`, which changes at communication points only).
    pub fn is_continuous(self) -> bool {
        self.kind() == Kind::Real && self.causality() != Causality::Parameter && self != Id::TSwitch
    }
}

/// One row of the table, as the model description shows it.
#[derive(Clone, Debug)]
pub struct Variable {
    /// What it is.
    pub id: Id,
    /// Its public name.
    pub name: String,
    /// Its description in the model description.
    pub description: String,
    /// A `SimpleType` of [`TYPES`], for Reals.
    pub declared_type: Option<&'static str>,
    /// Start value of parameters and inputs, as written in the XML.
    pub start: Option<String>,
}

/// Simple types: (name, quantity, unit). Units are declared in [`UNITS`].
pub const TYPES: &[(&str, &str, &str)] = &[
    ("Mass", "Mass", "kg"),
    ("Time", "Time", "s"),
    ("Displacement", "Length", "m"),
    ("Velocity", "Velocity", "m/s"),
    ("Acceleration", "Acceleration", "m/s2"),
    ("Force", "Force", "N"),
    ("Energy", "Energy", "J"),
    ("Ratio", "", "1"),
];

/// Units with their SI base-unit exponents (kg, m, s).
pub const UNITS: &[(&str, i32, i32, i32)] = &[
    ("1", 0, 0, 0),
    ("kg", 1, 0, 0),
    ("s", 0, 0, 1),
    ("m", 0, 1, 0),
    ("m/s", 0, 1, -1),
    ("m/s2", 0, 1, -2),
    ("N", 1, 1, -2),
    ("J", 1, 2, -2),
];

fn real(v: f64) -> Option<String> {
    Some(format!("{v:?}"))
}

/// Every variable, in model-description order.
pub fn table() -> Vec<Variable> {
    let d = Params::default();
    let mut t = vec![];
    // `{j}` in a description is the block / interface number of the variable.
    let mut add = |id: Id, ty: Option<&'static str>, start: Option<String>, desc: &str| {
        let description = match id.block() {
            Some(j) => desc.replace("{j}", &j.to_string()),
            None => desc.to_string(),
        };
        t.push(Variable {
            id,
            name: id.name(),
            description,
            declared_type: ty,
            start,
        })
    };
    add(
        Id::NBlocks,
        None,
        Some(d.n_blocks.to_string()),
        "Number of blocks in the stack, 0 to 8",
    );
    add(
        Id::Mp,
        Some("Mass"),
        real(d.mp),
        "Mass of the primary structure",
    );
    add(
        Id::Tp,
        Some("Time"),
        real(d.tp),
        "Period of the bare structure, 2 pi sqrt(mp / k)",
    );
    add(
        Id::Zeta,
        Some("Ratio"),
        real(d.zeta),
        "Damping ratio of the bare structure",
    );
    add(
        Id::G,
        Some("Acceleration"),
        real(d.g),
        "Gravitational acceleration",
    );
    for j in 1..=MAX_BLOCKS {
        add(
            Id::Alpha(j),
            Some("Ratio"),
            real(d.alpha[j - 1]),
            "Mass of block {j} over mp",
        );
    }
    for j in 1..=MAX_BLOCKS {
        add(
            Id::Mus(j),
            Some("Ratio"),
            real(d.mus[j - 1]),
            "Static friction coefficient of interface {j} (below block {j})",
        );
    }
    for j in 1..=MAX_BLOCKS {
        add(
            Id::Muk(j),
            Some("Ratio"),
            real(d.muk[j - 1]),
            "Kinetic friction coefficient of interface {j}, <= mus[{j}]",
        );
    }
    add(Id::RecordFile, None, Some(String::new()), "Ground-motion file (PEER .AT2 in g, or CSV time,accel in m/s2), absolute or relative to the resources folder; empty: none");
    add(
        Id::RecordScale,
        Some("Ratio"),
        real(1.0),
        "Factor on the record's acceleration",
    );
    add(
        Id::Solver,
        None,
        Some("1".to_string()),
        "1: exact (default): the exact motion of each stick/slip mode, switches located on it; 2: RK4 with mode switches at step ends only (the paper's method, baseline); 3: tanh-regularized friction, plain RK4 (baseline)",
    );
    add(
        Id::MaxStep,
        Some("Time"),
        real(0.0),
        "Largest internal step (s); 0: automatic. Solver 1 stays exact at any value (a smaller one only costs time); solver 2 uses it as its RK4 step within the stability bound; solver 3 as its fixed step, with no stability bound",
    );
    add(
        Id::FrictionEps,
        Some("Velocity"),
        real(crate::physics::solver::DEFAULT_FRICTION_EPS),
        "Solver 3 only: friction is -muk N tanh(v / frictionEps)",
    );
    add(
        Id::Ag,
        Some("Acceleration"),
        real(0.0),
        "Ground (support) acceleration, added to the record's",
    );
    add(
        Id::Fext,
        Some("Force"),
        real(0.0),
        "External force on the structure",
    );
    add(
        Id::Up,
        Some("Displacement"),
        None,
        "Structure displacement relative to the support",
    );
    add(
        Id::Vp,
        Some("Velocity"),
        None,
        "Structure velocity relative to the support",
    );
    add(
        Id::ApAbs,
        Some("Acceleration"),
        None,
        "Structure absolute acceleration",
    );
    add(
        Id::BaseShear,
        Some("Force"),
        None,
        "Force on the support, k up + c vp",
    );
    let per_block: [(fn(usize) -> Id, &'static str, &str); 6] = [
        (
            Id::Ub,
            "Displacement",
            "Block {j} displacement relative to the support",
        ),
        (
            Id::Vb,
            "Velocity",
            "Block {j} velocity relative to the support",
        ),
        (
            Id::Slip,
            "Displacement",
            "Block {j} displacement relative to the body below",
        ),
        (Id::AbAbs, "Acceleration", "Block {j} absolute acceleration"),
        (
            Id::F,
            "Force",
            "Friction force of interface {j} on block {j}",
        ),
        (
            Id::PeakSlip,
            "Displacement",
            "Largest |slip[{j}]| since the start",
        ),
    ];
    for (make, ty, desc) in per_block {
        for j in 1..=MAX_BLOCKS {
            add(make(j), Some(ty), None, desc);
        }
    }
    for j in 1..=MAX_BLOCKS {
        add(Id::Stuck(j), None, None, "Interface {j} is stuck");
    }
    add(
        Id::PeakUp,
        Some("Displacement"),
        None,
        "Largest |up| since the start",
    );
    add(
        Id::PeakApAbs,
        Some("Acceleration"),
        None,
        "Largest |apAbs| since the start",
    );
    add(
        Id::Einput,
        Some("Energy"),
        None,
        "Input energy (relative coordinates)",
    );
    add(
        Id::Ekinetic,
        Some("Energy"),
        None,
        "Kinetic energy (relative coordinates)",
    );
    add(
        Id::Estrain,
        Some("Energy"),
        None,
        "Strain energy of the structure",
    );
    add(
        Id::Eviscous,
        Some("Energy"),
        None,
        "Energy dissipated by the damper",
    );
    add(
        Id::Efriction,
        Some("Energy"),
        None,
        "Energy dissipated by friction",
    );
    add(
        Id::TSwitch,
        Some("Time"),
        None,
        "Time of the first stick/slip switch inside the last fmi2DoStep (its start if the step began with one); the step's end if there was none",
    );
    add(
        Id::NEvents,
        None,
        None,
        "Number of stick/slip mode switches (solver 3: steps where a relative velocity changed sign)",
    );
    add(
        Id::NAmbiguous,
        None,
        None,
        "Mode resolutions where several stick/slip assignments were consistent (mus > muk) and the selection rule chose",
    );
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn value_references_are_unique_and_decode_back() {
        let t = table();
        let mut seen = std::collections::HashSet::new();
        for v in &t {
            assert!(seen.insert(v.id.vr()), "duplicate vr {}", v.id.vr());
            assert_eq!(Id::from_vr(v.id.vr()), Some(v.id), "{}", v.name);
        }
        assert_eq!(Id::from_vr(10), None);
        assert_eq!(Id::from_vr(19), None);
        assert_eq!(Id::from_vr(8), None);
        let names: std::collections::HashSet<_> = t.iter().map(|v| v.name.as_str()).collect();
        assert_eq!(names.len(), t.len());
        assert_eq!(Id::Alpha(2).name(), "alpha[2]");
    }

    #[test]
    fn declared_ranges_are_the_checked_ones() {
        use crate::physics::params::check_scalar;
        let mut with_range = 0;
        for v in table() {
            let Some((lo, hi)) = v.id.range() else {
                continue;
            };
            with_range += 1;
            if v.id.kind() == Kind::Real {
                // Both ends are accepted, just outside them is refused.
                assert!(check_scalar(&v.name, lo).is_ok(), "{} min", v.name);
                assert!(
                    check_scalar(&v.name, lo - 1e-3 * lo.abs().max(1e-3)).is_err(),
                    "{}",
                    v.name
                );
                if let Some(hi) = hi {
                    assert!(check_scalar(&v.name, hi).is_ok(), "{} max", v.name);
                    assert!(
                        check_scalar(&v.name, hi * (1.0 + 1e-9) + 1e-12).is_err(),
                        "{}",
                        v.name
                    );
                }
            }
        }
        // Every parameter and input but recordFile has a range.
        let settable = table()
            .iter()
            .filter(|v| v.id.causality() != Causality::Output && v.id.kind() != Kind::String)
            .count();
        assert_eq!(with_range, settable);
        assert_eq!(Id::NBlocks.range(), Some((0.0, Some(8.0))));
        assert_eq!(Id::Solver.range(), Some((1.0, Some(3.0))));
    }
}
