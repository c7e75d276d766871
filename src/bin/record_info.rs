//! Prints what the Rust reader makes of a record, as JSON (NPTS, DT, PGA in
//! g): the Python reader is checked against it.
use stacked_live_load::GroundMotion;

fn main() {
    let path = std::env::args().nth(1).expect("usage: record_info FILE");
    match GroundMotion::read(std::path::Path::new(&path), 1.0) {
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
