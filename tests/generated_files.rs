//! The committed generated files must equal what the code generates now.
//! Run with UPDATE_GENERATED=1 to rewrite them.

use std::path::Path;

fn check(committed: &str, generated: &str) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(committed);
    if std::env::var_os("UPDATE_GENERATED").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, generated).unwrap();
    }
    let on_disk = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        on_disk == generated,
        "{committed} is stale: run `UPDATE_GENERATED=1 cargo test --test generated_files` and commit it"
    );
}

#[test]
fn model_description_is_fresh() {
    check(
        "modelDescription/modelDescription.xml",
        &stacked_live_load::fmi::model_description::model_description(),
    );
}

#[test]
fn fmi3_model_description_is_fresh() {
    check(
        "modelDescription/fmi3/modelDescription.xml",
        &stacked_live_load::fmi::model_description_fmi3::model_description(),
    );
}

#[test]
fn stack_on_floor_model_descriptions_are_fresh() {
    use stacked_live_load::fmi::variables::Model;
    check(
        "modelDescription/StackOnFloor/modelDescription.xml",
        &stacked_live_load::fmi::model_description::model_description_of(Model::Floor),
    );
    check(
        "modelDescription/StackOnFloor/fmi3/modelDescription.xml",
        &stacked_live_load::fmi::model_description_fmi3::model_description_of(Model::Floor),
    );
}

#[test]
fn c_header_is_fresh() {
    let crate_dir = env!("CARGO_MANIFEST_DIR");
    let config = cbindgen::Config::from_root_or_default(crate_dir);
    let mut out = Vec::new();
    cbindgen::Builder::new()
        .with_crate(crate_dir)
        .with_config(config)
        .generate()
        .expect("cbindgen parses the crate")
        .write(&mut out);
    check(
        "include/StackedLiveLoad.h",
        &String::from_utf8(out).unwrap(),
    );
}
