//! The FMU: the FMI 2.0 and FMI 3.0 layers over the physics and the ground motion. It knows the variables and
//! the FMI state machine, nothing of friction beyond the variable table.
//!
//! - [`c_api`]: the exported C functions (thin, panic-safe wrappers).
//! - [`instance`]: one FMU instance as safe Rust: the FMI state machine.
//! - [`variables`]: the variable table (names, value references, starts).
//! - [`model_description`], [`model_description_fmi3`]: the FMI 2.0 and 3.0
//!   `modelDescription.xml`, generated from the table.
//! - [`ports`]: the outputs' input dependencies and time derivatives.
//! - [`resource_location`]: `fmuResourceLocation` (a `file:` URI) as a folder.

pub mod c_api;
pub mod instance;
pub mod model_description;
pub mod model_description_fmi3;
pub mod ports;
pub mod resource_location;
pub mod variables;
