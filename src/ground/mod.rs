//! Ground motion: record files (PEER AT2, CSV, single column), driving a
//! simulation through a record, and the embedded default record.
//!
//! - [`record`]: the [`GroundMotion`](record::GroundMotion) table and
//!   stepping a simulator through one.
//! - [`formats`]: the file readers, `GroundMotion::read`,
//!   `from_csv_text` and `from_single_column`, with their safety limits, and
//!   the fingerprint of a file's content (the FMU's record cache).
//! - [`synthetic`]: broadband synthetic records and the embedded default.

pub mod formats;
pub mod record;
pub mod synthetic;
