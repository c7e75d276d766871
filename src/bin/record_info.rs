//! Prints what the Rust reader makes of a record, as JSON (NPTS, DT, PGA in
//! the file's units): the Python reader is checked against it.
//!
//! record_info FILE            (.AT2 or CSV)
//! record_info FILE DT         (single column, sampled every DT)
use stacked_live_load::GroundMotion;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = args.first().expect("usage: record_info FILE [DT]");
    let read = match args.get(1) {
        Some(dt) => std::fs::read_to_string(path)
            .map_err(|e| format!("{path}: {e}"))
            .and_then(|text| {
                let dt: f64 = dt
                    .parse()
                    .map_err(|_| format!("DT `{dt}` is not a number"))?;
                GroundMotion::from_single_column(&text, path, dt, 1.0).map_err(|e| e.to_string())
            }),
        None => GroundMotion::read(std::path::Path::new(path), 1.0).map_err(|e| e.to_string()),
    };
    match read {
        Ok(gm) => println!(
            "{{\"npts\": {}, \"dt\": {:?}, \"duration\": {:?}, \"pga\": {:?}}}",
            gm.time.len(),
            gm.time[1] - gm.time[0],
            gm.duration(),
            gm.pga()
        ),
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    }
}
