//! The FMUs' variables: one table per model that both the get/set functions
//! and the generated `modelDescription.xml` read. Names and value references
//! are the public interface; value references are unique across all types
//! and shared by the models (a variable of both has the same reference).
//!
//! One binary holds two models ([`Model`]): `StackedLiveLoad`, the stack on
//! an SDOF structure, and `StackOnFloor`, the stack on a support whose
//! absolute acceleration is an input. The importer's GUID / instantiation
//! token picks the model; each model has its own table ([`Model::table`]).

use crate::physics::params::{check_scalar, ParamError, Params, MAX_BLOCKS, RANGES};
use crate::solver::SolverKind;

/// The models of this binary.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Model {
    /// `StackedLiveLoad`: a linear SDOF structure carrying the stack.
    Storey,
    /// `StackOnFloor`: the stack on a support whose absolute acceleration
    /// is the input `ag` (the floor of another model).
    Floor,
}

impl Model {
    /// Every model of the binary.
    pub const ALL: [Model; 2] = [Model::Storey, Model::Floor];

    /// The model identifier: the FMU's and its binary's name.
    pub fn identifier(self) -> &'static str {
        match self {
            Model::Storey => "StackedLiveLoad",
            Model::Floor => "StackOnFloor",
        }
    }

    /// The GUID (FMI 2.0) and instantiation token (FMI 3.0) of its model
    /// description ([`crate::fmi::c_api::GUID`], [`crate::fmi::c_api::FLOOR_GUID`]).
    pub const fn guid(self) -> &'static str {
        match self {
            Model::Storey => crate::fmi::c_api::GUID,
            Model::Floor => crate::fmi::c_api::FLOOR_GUID,
        }
    }

    /// The model whose GUID / instantiation token is `token`.
    pub fn from_token(token: &str) -> Option<Model> {
        Model::ALL.into_iter().find(|m| m.guid() == token)
    }

    /// Its variables, in model-description order.
    pub fn table(self) -> Vec<Variable> {
        match self {
            Model::Storey => table(),
            Model::Floor => floor_table(),
        }
    }

    /// Whether variable `id` belongs to the model: whether its table lists
    /// it (the table is the one definition; its value references are kept
    /// sorted once per model for the lookups of every get and set).
    pub fn has(self, id: Id) -> bool {
        static VRS: [std::sync::OnceLock<Vec<u32>>; 2] =
            [std::sync::OnceLock::new(), std::sync::OnceLock::new()];
        let slot = match self {
            Model::Storey => 0,
            Model::Floor => 1,
        };
        VRS[slot]
            .get_or_init(|| {
                let mut vrs: Vec<u32> = self.table().iter().map(|v| v.id.vr()).collect();
                vrs.sort_unstable();
                vrs
            })
            .binary_search(&id.vr())
            .is_ok()
    }

    /// The model's variable with value reference `vr`, if any.
    pub fn lookup(self, vr: u32) -> Option<Id> {
        Id::from_vr(vr).filter(|&id| self.has(id))
    }

    /// The range the model enforces on a parameter or input ([`Id::range`]):
    /// a StackOnFloor has at least one block.
    pub fn range(self, id: Id) -> Option<(f64, Option<f64>)> {
        match (self, id) {
            (Model::Floor, Id::NBlocks) => Some((1.0, Some(MAX_BLOCKS as f64))),
            _ => id.range(),
        }
    }

    /// The inputs output `id` depends on at the same instant (direct
    /// feedthrough; docs/coupling-ports.md).
    ///
    /// StackOnFloor: the cluster stuck to the support moves with it, so its
    /// blocks' absolute accelerations, the forces of its stuck interfaces
    /// and the force on the floor follow `ag` at once; a jump of `ag` can
    /// break a stick of that cluster, and `supportMobility` enters the
    /// resolution of the mode, so the stick flags, the attached mass and
    /// the sliding force (constant within a mode) change with either, as
    /// may the force and acceleration of any block (any block can be in
    /// that cluster). Displacements, velocities, slips, peaks, energies and
    /// counters are state only.
    pub fn input_dependencies(self, id: Id) -> &'static [Id] {
        match self {
            Model::Storey => id.input_dependencies(),
            Model::Floor => match id {
                Id::FloorForce
                | Id::AttachedMass
                | Id::SlidingForce
                | Id::AbAbs(_)
                | Id::F(_)
                | Id::Stuck(_) => &[Id::Ag, Id::SupportMobility],
                _ => &[],
            },
        }
    }

    /// The model's one-sentence description.
    pub fn description(self) -> &'static str {
        match self {
            Model::Storey => {
                "Linear SDOF structure carrying a stack of up to 8 rigid blocks that stick or \
                 slide with Coulomb friction, under ground acceleration; exact stick/slip events"
            }
            Model::Floor => {
                "A stack of 1 to 8 rigid blocks that stick or slide with Coulomb friction on a \
                 rigid support (the floor of another model) whose absolute acceleration is the \
                 input ag; the force on the floor is an output; exact stick/slip events"
            }
        }
    }
}

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
    /// StackOnFloor: mass of block j (kg).
    M(usize),
    // Real inputs
    Ag,
    Fext,
    SupportMobility,
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
    FloorForce,
    AttachedMass,
    SlidingForce,
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
            Id::M(j) => at(40, j),
            Id::Ag => 100,
            Id::Fext => 101,
            Id::SupportMobility => 102,
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
            Id::FloorForce => 212,
            Id::AttachedMass => 213,
            Id::SlidingForce => 214,
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
            40..=49 => array(Id::M),
            100 => Some(Id::Ag),
            101 => Some(Id::Fext),
            102 => Some(Id::SupportMobility),
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
            212 => Some(Id::FloorForce),
            213 => Some(Id::AttachedMass),
            214 => Some(Id::SlidingForce),
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
            Id::M(j) => indexed("m", j),
            Id::Ag => "ag".into(),
            Id::Fext => "Fext".into(),
            Id::SupportMobility => "supportMobility".into(),
            Id::FloorForce => "floorForce".into(),
            Id::AttachedMass => "attachedMass".into(),
            Id::SlidingForce => "slidingForce".into(),
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
            | Id::M(_)
            | Id::NBlocks
            | Id::Solver
            | Id::RecordFile => Causality::Parameter,
            Id::Ag | Id::Fext | Id::SupportMobility => Causality::Input,
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
            | Id::M(j)
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
        let name = self.range_name();
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

    /// The name its range has in [`RANGES`]: its own, but `m[j]`, which
    /// is checked as `alpha[j]` (StackOnFloor's mass ratios to `mp = 1 kg`).
    fn range_name(self) -> String {
        match self {
            Id::M(j) => format!("alpha[{j}]"),
            _ => self.name(),
        }
    }

    /// Checks a value of this Real parameter or input against its range
    /// ([`check_scalar`]); the error names the variable.
    pub fn check(self, x: f64) -> Result<(), ParamError> {
        check_scalar(&self.range_name(), x).map_err(|e| ParamError {
            field: self.name(),
            allowed: match self {
                Id::M(_) => format!("{} (kg)", e.allowed),
                _ => e.allowed,
            },
            ..e
        })
    }

    /// Whether the variable varies continuously in time (Real inputs and
    /// Real outputs but `tSwitch`, which changes at communication points only).
    pub fn is_continuous(self) -> bool {
        self.kind() == Kind::Real
            && self.causality() != Causality::Parameter
            && !matches!(
                self,
                Id::TSwitch | Id::AttachedMass | Id::SlidingForce | Id::SupportMobility
            )
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
    ("Mobility", "", "1/kg"),
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
    ("1/kg", -1, 0, 0),
];

fn real(v: f64) -> Option<String> {
    Some(format!("{v:?}"))
}

/// A per-block variable: its id from the block's index, its quantity and
/// its description (with `{j}` for the block's number).
type PerBlock = (fn(usize) -> Id, &'static str, &'static str);

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
        real(crate::solver::DEFAULT_FRICTION_EPS),
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
    let per_block: [PerBlock; 6] = [
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

/// StackOnFloor's default mass of each block (kg): the storey's default
/// blocks (alpha 0.25 of 1000 kg).
pub const FLOOR_DEFAULT_MASS: f64 = 250.0;

/// StackOnFloor's variables, in model-description order: the storey's block
/// quantities under the same names and value references, the masses of the
/// blocks, the support's acceleration and mobility as inputs, and the force
/// on the floor.
fn floor_table() -> Vec<Variable> {
    let storey = table();
    let from_storey = |id: Id| {
        let mut v = storey
            .iter()
            .find(|v| v.id == id)
            .expect("a shared variable is in the storey's table")
            .clone();
        if id == Id::NBlocks {
            v.description = "Number of blocks in the stack, 1 to 8".into();
        }
        v
    };
    let own = |id: Id, ty: &'static str, start: Option<String>, desc: &str| Variable {
        id,
        name: id.name(),
        description: match id.block() {
            Some(j) => desc.replace("{j}", &j.to_string()),
            None => desc.to_string(),
        },
        declared_type: Some(ty),
        start,
    };
    let mut t = vec![from_storey(Id::NBlocks), from_storey(Id::G)];
    for j in 1..=MAX_BLOCKS {
        t.push(own(
            Id::M(j),
            "Mass",
            real(FLOOR_DEFAULT_MASS),
            "Mass of block {j} (block 1 rests on the support, block j on block j - 1)",
        ));
    }
    let shared = |make: fn(usize) -> Id| (1..=MAX_BLOCKS).map(make);
    t.extend(shared(Id::Mus).chain(shared(Id::Muk)).map(from_storey));
    t.extend([Id::RecordFile, Id::RecordScale].map(from_storey));
    t.push(own(
        Id::Ag,
        "Acceleration",
        real(0.0),
        "Absolute acceleration of the support (the floor the stack stands on), added to the record's",
    ));
    t.push(own(
        Id::SupportMobility,
        "Mobility",
        real(0.0),
        "d(floor acceleration)/d(floorForce) of the model the floor belongs to (its interface \
         Jacobian, 1/kg), used to choose the stick/slip mode at a switch; 0: the support's motion \
         is prescribed",
    ));
    t.push(own(
        Id::FloorForce,
        "Force",
        None,
        "Force the stack puts on the support along +x (= -F[1]); the partner applies +floorForce to its floor",
    ));
    t.push(own(
        Id::AttachedMass,
        "Mass",
        None,
        "Mass of the blocks stuck to the support now (0 if interface 1 slips): floorForce = slidingForce - attachedMass ag",
    ));
    t.push(own(
        Id::SlidingForce,
        "Force",
        None,
        "floorForce + attachedMass ag: the friction force from the first slipping interface, constant between stick/slip switches",
    ));
    for make in [
        Id::Ub,
        Id::Vb,
        Id::Slip,
        Id::AbAbs,
        Id::F,
        Id::PeakSlip,
        Id::Stuck,
    ] {
        t.extend(shared(make).map(from_storey));
    }
    t.extend(
        [
            Id::Einput,
            Id::Ekinetic,
            Id::Efriction,
            Id::TSwitch,
            Id::NEvents,
            Id::NAmbiguous,
        ]
        .map(from_storey),
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

    #[test]
    fn the_floor_table_shares_names_and_references_and_checks_its_ranges() {
        let storey = table();
        let floor = Model::Floor.table();
        let mut seen = std::collections::HashSet::new();
        for v in &floor {
            assert!(seen.insert(v.id.vr()), "duplicate vr {}", v.id.vr());
            assert!(Model::Floor.has(v.id), "{}", v.name);
            assert_eq!(Model::Floor.lookup(v.id.vr()), Some(v.id));
            // A name of both models has the same value reference.
            if let Some(w) = storey.iter().find(|w| w.name == v.name) {
                assert_eq!(w.id.vr(), v.id.vr(), "{}", v.name);
            } else {
                assert_eq!(Model::Storey.lookup(v.id.vr()), None, "{}", v.name);
            }
            if let Some((lo, hi)) = Model::Floor.range(v.id) {
                if v.id.kind() == Kind::Real {
                    assert!(v.id.check(lo).is_ok(), "{} min", v.name);
                    assert!(
                        v.id.check(lo - 1e-3 * lo.abs().max(1e-3)).is_err(),
                        "{}",
                        v.name
                    );
                    let hi = hi.expect("every Real range has a max");
                    assert!(v.id.check(hi).is_ok(), "{} max", v.name);
                    assert!(v.id.check(hi * (1.0 + 1e-9)).is_err(), "{} above", v.name);
                }
            }
        }
        for v in &storey {
            assert!(Model::Storey.has(v.id), "{}", v.name);
        }
        assert_eq!(Model::Floor.range(Id::NBlocks), Some((1.0, Some(8.0))));
        assert_eq!(Id::M(2).check(-1.0).unwrap_err().field, "m[2]");
        assert!(Model::Floor.lookup(Id::Mp.vr()).is_none());
        assert!(Model::Storey.lookup(Id::SupportMobility.vr()).is_none());
        assert_eq!(Model::from_token(Model::Floor.guid()), Some(Model::Floor));
        assert_eq!(Model::from_token("{}"), None);
    }
}
