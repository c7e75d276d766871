//! Ground motion: record files (PEER AT2, CSV, single column), driving a
//! simulation through a record, and the embedded default record.
//!
//! - [`record`]: the [`GroundMotion`](record::GroundMotion) table and
//!   stepping a simulator through one.
//! - `formats` (private): the file readers, `GroundMotion::read`,
//!   `from_csv_text` and `from_single_column`, with their safety limits.
//! - [`synthetic`]: broadband synthetic records and the embedded default.

mod formats;
pub mod record;
pub mod synthetic;
