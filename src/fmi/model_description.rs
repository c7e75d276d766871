//! `modelDescription.xml`, generated with quick-xml from the variable table.

use crate::fmi::variables::{Causality, Id, Kind, Model, Variable, TYPES, UNITS};
use quick_xml::events::{BytesDecl, Event};
use quick_xml::Writer;
use std::io;

/// The storey model's identifier: the shared library's and the FMU's name.
pub const MODEL_IDENTIFIER: &str = "StackedLiveLoad";

/// The generation tool (both FMI versions).
pub(super) fn tool() -> String {
    format!("stacked-live-load {}", env!("CARGO_PKG_VERSION"))
}

/// The log categories (both FMI versions).
const LOG_CATEGORIES: [(&str, &str); 3] = [
    (
        "logStatusError",
        "Errors: bad input, illegal calls, unreadable records",
    ),
    (
        "logStatusFatal",
        "Internal errors caught at the C interface",
    ),
    ("logAll", "Diagnostics, when debug logging is on"),
];

/// The default experiment: the embedded default record (both FMI versions).
const DEFAULT_EXPERIMENT: [(&str, &str); 3] = [
    ("startTime", "0.0"),
    ("stopTime", "20.0"),
    ("stepSize", "0.005"),
];

/// The whole model description of the storey (StackedLiveLoad), UTF-8, deterministic.
pub fn model_description() -> String {
    model_description_of(Model::Storey)
}

/// The whole FMI 2.0 model description of `model`, UTF-8, deterministic.
pub fn model_description_of(model: Model) -> String {
    render(model, write)
}

/// An XML document written by `write` after the declaration (both FMI
/// versions): UTF-8, indented, deterministic.
pub(super) fn render(
    model: Model,
    write: fn(&mut Writer<Vec<u8>>, Model) -> io::Result<()>,
) -> String {
    let mut w = Writer::new_with_indent(Vec::new(), b' ', 2);
    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))
        .and_then(|_| write(&mut w, model))
        .expect("writing to memory cannot fail");
    let mut text = String::from_utf8(w.into_inner()).expect("UTF-8");
    text.push('\n');
    text
}

fn write(w: &mut Writer<Vec<u8>>, model: Model) -> io::Result<()> {
    let description = model.description();
    let tool = tool();
    let variables = model.table();
    w.create_element("fmiModelDescription")
        .with_attributes([
            ("fmiVersion", "2.0"),
            ("modelName", model.identifier()),
            ("guid", model.guid()),
            ("description", description),
            ("generationTool", tool.as_str()),
            ("variableNamingConvention", "structured"),
            ("numberOfEventIndicators", "0"),
        ])
        .write_inner_content(|w| {
            w.create_element("CoSimulation")
                .with_attributes([
                    ("modelIdentifier", model.identifier()),
                    ("canHandleVariableCommunicationStepSize", "true"),
                    ("canInterpolateInputs", "true"),
                    ("maxOutputDerivativeOrder", "2"),
                    ("canGetAndSetFMUstate", "true"),
                    ("canSerializeFMUstate", "true"),
                    ("canNotUseMemoryManagementFunctions", "true"),
                    ("canBeInstantiatedOnlyOncePerProcess", "false"),
                    ("providesDirectionalDerivative", "true"),
                ])
                .write_empty()?;
            write_units(w, &variables)?;
            write_types(w, &variables)?;
            write_log_categories_and_experiment(w)?;
            w.create_element("ModelVariables")
                .write_inner_content(|w| {
                    for v in &variables {
                        write_variable(w, model, v)?;
                    }
                    Ok(())
                })?;
            write_structure(w, model, &variables)
        })?;
    Ok(())
}

/// `LogCategories` and `DefaultExperiment` (both FMI versions).
pub(super) fn write_log_categories_and_experiment(w: &mut Writer<Vec<u8>>) -> io::Result<()> {
    w.create_element("LogCategories").write_inner_content(|w| {
        for (name, text) in LOG_CATEGORIES {
            w.create_element("Category")
                .with_attributes([("name", name), ("description", text)])
                .write_empty()?;
        }
        Ok(())
    })?;
    w.create_element("DefaultExperiment")
        .with_attributes(DEFAULT_EXPERIMENT)
        .write_empty()?;
    Ok(())
}

/// The simple types the variables of a model use, in [`TYPES`] order.
pub(super) fn types_used(
    variables: &[Variable],
) -> Vec<(&'static str, &'static str, &'static str)> {
    TYPES
        .iter()
        .filter(|t| variables.iter().any(|v| v.declared_type == Some(t.0)))
        .copied()
        .collect()
}

/// The units of the types a model uses, in [`UNITS`] order.
pub(super) fn write_units(w: &mut Writer<Vec<u8>>, variables: &[Variable]) -> io::Result<()> {
    let types = types_used(variables);
    w.create_element("UnitDefinitions")
        .write_inner_content(|w| {
            for &(name, kg, m, s) in UNITS.iter().filter(|u| types.iter().any(|t| t.2 == u.0)) {
                let exponents: Vec<(&str, String)> = [("kg", kg), ("m", m), ("s", s)]
                    .into_iter()
                    .filter(|&(_, e)| e != 0)
                    .map(|(k, e)| (k, e.to_string()))
                    .collect();
                w.create_element("Unit")
                    .with_attribute(("name", name))
                    .write_inner_content(|w| {
                        w.create_element("BaseUnit")
                            .with_attributes(exponents.iter().map(|(k, e)| (*k, e.as_str())))
                            .write_empty()?;
                        Ok(())
                    })?;
            }
            Ok(())
        })?;
    Ok(())
}

fn write_types(w: &mut Writer<Vec<u8>>, variables: &[Variable]) -> io::Result<()> {
    w.create_element("TypeDefinitions")
        .write_inner_content(|w| {
            for (name, quantity, unit) in types_used(variables) {
                w.create_element("SimpleType")
                    .with_attribute(("name", name))
                    .write_inner_content(|w| {
                        let mut attrs = vec![("unit", unit)];
                        if !quantity.is_empty() {
                            attrs.insert(0, ("quantity", quantity));
                        }
                        w.create_element("Real")
                            .with_attributes(attrs)
                            .write_empty()?;
                        Ok(())
                    })?;
            }
            Ok(())
        })?;
    Ok(())
}

/// `causality` and `variability` of a variable (both FMI versions).
pub(super) fn causality_and_variability(id: Id) -> (&'static str, &'static str) {
    match (id.causality(), id.kind()) {
        (Causality::Parameter, _) => ("parameter", "fixed"),
        (Causality::Input, _) if id.is_continuous() => ("input", "continuous"),
        (Causality::Input, _) => ("input", "discrete"),
        (Causality::Output, Kind::Real) if id.is_continuous() => ("output", "continuous"),
        (Causality::Output, _) => ("output", "discrete"),
    }
}

fn write_variable(w: &mut Writer<Vec<u8>>, model: Model, v: &Variable) -> io::Result<()> {
    let kind = v.id.kind();
    let (causality, variability) = causality_and_variability(v.id);
    let vr = v.id.vr().to_string();
    w.create_element("ScalarVariable")
        .with_attributes([
            ("name", v.name.as_str()),
            ("valueReference", vr.as_str()),
            ("description", v.description.as_str()),
            ("causality", causality),
            ("variability", variability),
        ])
        .write_inner_content(|w| {
            let element = match kind {
                Kind::Real => "Real",
                Kind::Integer => "Integer",
                Kind::Boolean => "Boolean",
                Kind::String => "String",
            };
            let mut attrs: Vec<(&str, &str)> = vec![];
            if let Some(t) = v.declared_type {
                attrs.push(("declaredType", t));
            }
            if let Some(s) = &v.start {
                attrs.push(("start", s.as_str()));
            }
            let bounds = bounds(model, v.id);
            attrs.extend(bounds.iter().map(|(k, x)| (*k, x.as_str())));
            w.create_element(element)
                .with_attributes(attrs)
                .write_empty()?;
            Ok(())
        })?;
    Ok(())
}

/// `min` and `max` of a variable with a range ([`Model::range`]), as written in
/// the XML (integers without a decimal point).
pub(super) fn bounds(model: Model, id: Id) -> Vec<(&'static str, String)> {
    let number = |x: f64| match id.kind() {
        Kind::Real => format!("{x:?}"),
        _ => format!("{}", x as i64),
    };
    let Some((lo, hi)) = model.range(id) else {
        return vec![];
    };
    let mut out = vec![("min", number(lo))];
    out.extend(hi.map(|hi| ("max", number(hi))));
    out
}

/// Every output is listed in `Outputs` with the inputs it depends on at the
/// same instant, and, being calculated at initialization, in
/// `InitialUnknowns`, where every parameter is a known too (the outputs at
/// the start depend on the scene). Indices are 1-based positions.
fn write_structure(
    w: &mut Writer<Vec<u8>>,
    model: Model,
    variables: &[Variable],
) -> io::Result<()> {
    let index_of = |id: Id| {
        let i = variables.iter().position(|v| v.id == id);
        (i.expect("every input is in the table") + 1).to_string()
    };
    let parameters: Vec<String> = variables
        .iter()
        .enumerate()
        .filter(|(_, v)| v.id.causality() == Causality::Parameter)
        .map(|(i, _)| (i + 1).to_string())
        .collect();
    let outputs: Vec<(String, Vec<String>)> = variables
        .iter()
        .enumerate()
        .filter(|(_, v)| v.id.causality() == Causality::Output)
        .map(|(i, v)| {
            let inputs = model
                .input_dependencies(v.id)
                .iter()
                .map(|&id| index_of(id));
            ((i + 1).to_string(), inputs.collect())
        })
        .collect();
    w.create_element("ModelStructure")
        .write_inner_content(|w| {
            for section in ["Outputs", "InitialUnknowns"] {
                w.create_element(section).write_inner_content(|w| {
                    for (index, inputs) in &outputs {
                        let mut knowns = inputs.clone();
                        if section == "InitialUnknowns" {
                            knowns.extend(parameters.iter().cloned());
                            knowns.sort_by_key(|k| k.parse::<usize>().unwrap_or(0));
                        }
                        let kinds = vec!["dependent"; knowns.len()].join(" ");
                        let knowns = knowns.join(" ");
                        w.create_element("Unknown")
                            .with_attributes([
                                ("index", index.as_str()),
                                ("dependencies", knowns.as_str()),
                                ("dependenciesKind", kinds.as_str()),
                            ])
                            .write_empty()?;
                    }
                    Ok(())
                })?;
            }
            Ok(())
        })?;
    Ok(())
}
