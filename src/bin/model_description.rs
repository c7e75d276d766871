//! Prints the generated modelDescription.xml (used by scripts/build_fmu.sh):
//! the FMI 2.0 one, or with the argument `3` the FMI 3.0 one.
fn main() {
    let fmi3 = std::env::args().nth(1).as_deref() == Some("3");
    print!(
        "{}",
        if fmi3 {
            stacked_live_load::fmi::model_description_fmi3::model_description()
        } else {
            stacked_live_load::fmi::model_description::model_description()
        }
    );
}
