//! The FMI 3.0 `modelDescription.xml`, generated from the same variable table
//! as the FMI 2.0 one ([`super::model_description`]): the same names and
//! value references, FMI 3.0 types (Float64, Int32, Boolean, String), the
//! independent variable `time` (value reference 0, FMI 3.0 only), and the
//! Co-Simulation capabilities of this ABI (early return, Event Mode).

use super::model_description::{
    bounds, causality_and_variability, render, tool, types_used,
    write_log_categories_and_experiment, write_units,
};
use crate::fmi::variables::{Causality, Id, Kind, Model, Variable};
use quick_xml::Writer;
use std::io;

/// The whole FMI 3.0 model description of the storey (StackedLiveLoad), UTF-8, deterministic.
pub fn model_description() -> String {
    model_description_of(Model::Storey)
}

/// The whole FMI 3.0 model description of `model`, UTF-8, deterministic.
pub fn model_description_of(model: Model) -> String {
    render(model, write)
}

fn write(w: &mut Writer<Vec<u8>>, model: Model) -> io::Result<()> {
    let tool = tool();
    let variables = model.table();
    w.create_element("fmiModelDescription")
        .with_attributes([
            ("fmiVersion", "3.0"),
            ("modelName", model.identifier()),
            ("instantiationToken", model.guid()),
            ("description", model.description()),
            ("generationTool", tool.as_str()),
            ("variableNamingConvention", "structured"),
        ])
        .write_inner_content(|w| {
            w.create_element("CoSimulation")
                .with_attributes([
                    ("modelIdentifier", model.identifier()),
                    ("canGetAndSetFMUState", "true"),
                    ("canSerializeFMUState", "true"),
                    ("providesDirectionalDerivatives", "true"),
                    ("providesAdjointDerivatives", "false"),
                    ("canBeInstantiatedOnlyOncePerProcess", "false"),
                    ("canHandleVariableCommunicationStepSize", "true"),
                    ("maxOutputDerivativeOrder", "2"),
                    ("hasEventMode", "true"),
                    ("mightReturnEarlyFromDoStep", "true"),
                    ("canReturnEarlyAfterIntermediateUpdate", "false"),
                    ("providesIntermediateUpdate", "false"),
                    ("providesEvaluateDiscreteStates", "false"),
                ])
                .write_empty()?;
            write_units(w, &variables)?;
            w.create_element("TypeDefinitions")
                .write_inner_content(|w| {
                    for (name, quantity, unit) in types_used(&variables) {
                        let mut attrs = vec![("name", name)];
                        if !quantity.is_empty() {
                            attrs.push(("quantity", quantity));
                        }
                        attrs.push(("unit", unit));
                        w.create_element("Float64Type")
                            .with_attributes(attrs)
                            .write_empty()?;
                    }
                    Ok(())
                })?;
            write_log_categories_and_experiment(w)?;
            w.create_element("ModelVariables")
                .write_inner_content(|w| {
                    w.create_element("Float64")
                        .with_attributes([
                            ("name", "time"),
                            ("valueReference", "0"),
                            ("description", "Simulation time"),
                            ("causality", "independent"),
                            ("variability", "continuous"),
                        ])
                        .write_empty()?;
                    for v in &variables {
                        write_variable(w, model, v)?;
                    }
                    Ok(())
                })?;
            write_structure(w, model, &variables)
        })?;
    Ok(())
}

fn write_variable(w: &mut Writer<Vec<u8>>, model: Model, v: &Variable) -> io::Result<()> {
    let kind = v.id.kind();
    let (causality, variability) = causality_and_variability(v.id);
    let element = match kind {
        Kind::Real => "Float64",
        Kind::Integer => "Int32",
        Kind::Boolean => "Boolean",
        Kind::String => "String",
    };
    let vr = v.id.vr().to_string();
    let mut attrs: Vec<(&str, &str)> = vec![
        ("name", v.name.as_str()),
        ("valueReference", vr.as_str()),
        ("description", v.description.as_str()),
        ("causality", causality),
        ("variability", variability),
    ];
    if let Some(t) = v.declared_type {
        attrs.push(("declaredType", t));
    }
    // A String's start is an element of its own.
    let start = v.start.as_deref();
    if kind != Kind::String {
        if let Some(s) = start {
            attrs.push(("start", s));
        }
    }
    let bounds = bounds(model, v.id);
    attrs.extend(bounds.iter().map(|(k, x)| (*k, x.as_str())));
    let e = w.create_element(element).with_attributes(attrs);
    match (kind, start) {
        (Kind::String, Some(s)) => {
            e.write_inner_content(|w| {
                w.create_element("Start")
                    .with_attribute(("value", s))
                    .write_empty()?;
                Ok(())
            })?;
        }
        _ => {
            e.write_empty()?;
        }
    }
    Ok(())
}

/// Every output in `Output` with the inputs it depends on at the same
/// instant and, being calculated at initialization, in `InitialUnknown`,
/// where the parameters are knowns too. FMI 3.0 names them by value reference.
fn write_structure(
    w: &mut Writer<Vec<u8>>,
    model: Model,
    variables: &[Variable],
) -> io::Result<()> {
    let parameters: Vec<u32> = variables
        .iter()
        .filter(|v| v.id.causality() == Causality::Parameter)
        .map(|v| v.id.vr())
        .collect();
    let outputs: Vec<(u32, Vec<u32>)> = variables
        .iter()
        .filter(|v| v.id.causality() == Causality::Output)
        .map(|v| {
            let inputs = model
                .input_dependencies(v.id)
                .iter()
                .map(|&id: &Id| id.vr());
            (v.id.vr(), inputs.collect())
        })
        .collect();
    w.create_element("ModelStructure")
        .write_inner_content(|w| {
            for section in ["Output", "InitialUnknown"] {
                for (vr, inputs) in &outputs {
                    let mut knowns = inputs.clone();
                    if section == "InitialUnknown" {
                        knowns.extend(parameters.iter().copied());
                        knowns.sort_unstable();
                    }
                    let kinds = vec!["dependent"; knowns.len()].join(" ");
                    let knowns: Vec<String> = knowns.iter().map(|k| k.to_string()).collect();
                    let (vr, knowns) = (vr.to_string(), knowns.join(" "));
                    let mut attrs = vec![
                        ("valueReference", vr.as_str()),
                        ("dependencies", knowns.as_str()),
                    ];
                    if !knowns.is_empty() {
                        attrs.push(("dependenciesKind", kinds.as_str()));
                    }
                    w.create_element(section)
                        .with_attributes(attrs)
                        .write_empty()?;
                }
            }
            Ok(())
        })?;
    Ok(())
}
