//! Writes the seed of the embedded default record as CSV `time,accel` (m/s2):
//! the deterministic broadband synthetic of `synthetic::broadband`, 20 s at
//! 0.005 s, PGA 0.36 g. `scripts/ground_motions.py default` matches it to the
//! IS 1893 Zone V hard-soil DBE spectrum into resources/default_record.csv.
fn main() {
    let gm = stacked_live_load::ground::synthetic::broadband(20.0, 0.005, 0.36 * 9.81);
    let mut out = String::from("time,accel\n");
    for (t, a) in gm.time.iter().zip(&gm.accel) {
        out.push_str(&format!("{t:?},{a:?}\n"));
    }
    print!("{out}");
}
