//! Prints the generated modelDescription.xml (used by scripts/build_fmu.sh).
fn main() {
    print!(
        "{}",
        stacked_live_load::fmi::model_description::model_description()
    );
}
