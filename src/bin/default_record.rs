//! Writes the embedded default ground motion as CSV `time,accel` (m/s2);
//! scripts/build_fmu.sh ships it as resources/default_record.csv.
fn main() {
    let gm = stacked_live_load::synthetic::default_record(9.81);
    let mut out = String::from("time,accel\n");
    for (t, a) in gm.time.iter().zip(&gm.accel) {
        out.push_str(&format!("{t:?},{a:?}\n"));
    }
    print!("{out}");
}
