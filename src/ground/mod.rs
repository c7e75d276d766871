//! Ground motion: record files (PEER AT2, CSV, single column), driving a
//! simulation through a record, and the embedded default record.
//!
//! - [`record`]: reading records and stepping a simulator through one.
//! - [`synthetic`]: broadband synthetic records and the embedded default.

pub mod record;
pub mod synthetic;
