//! Prints a generated modelDescription.xml (used by scripts/build_fmu.sh):
//! `model_description [2|3] [MODEL]` prints the FMI 2.0 (default) or FMI 3.0
//! one of model MODEL (`StackedLiveLoad`, the default, or `StackOnFloor`).
use stacked_live_load::fmi::variables::Model;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let fmi3 = args.first().map(String::as_str) == Some("3");
    let model = match args.get(1) {
        None => Model::Storey,
        Some(name) => {
            match Model::ALL.into_iter().find(|m| m.identifier() == name) {
                Some(model) => model,
                None => {
                    eprintln!("model_description: unknown model `{name}` (StackedLiveLoad or StackOnFloor)");
                    std::process::exit(2);
                }
            }
        }
    };
    print!(
        "{}",
        if fmi3 {
            stacked_live_load::fmi::model_description_fmi3::model_description_of(model)
        } else {
            stacked_live_load::fmi::model_description::model_description_of(model)
        }
    );
}
