//! Checks of a state read back from bytes (`fmi2DeSerializeFMUstate`): a
//! blob changed by a single bit must be refused, never lead to a panic, a
//! hang or a non-finite output. The scene and settings were validated when
//! the simulator was built; these are the dynamic fields.

use super::Simulator;
use crate::physics::mode::{Contact, Mode};
use crate::physics::params::MAX_BODIES;
use crate::physics::snapshot::{check_peaks, SnapshotError};

impl Simulator {
    /// The contact states: free exactly where mus = 0, as a fresh scene's
    /// beyond the stack (checked before the mode's dynamics are built).
    pub(super) fn check_restored_contacts(&self) -> Result<(), SnapshotError> {
        let fresh = Mode::all_stuck(&self.sys);
        for j in 0..MAX_BODIES {
            let c = self.mode.contact[j];
            let ok = if j == 0 || j > self.sys.n {
                c == fresh.contact[j]
            } else {
                (c == Contact::Free) == self.sys.is_free(j)
            };
            if !ok {
                return Err(format!(
                    "contact state {c:?} of interface {j} does not fit the stack of the saved state"
                ));
            }
        }
        Ok(())
    }

    /// Every other dynamic field: finite values, a time >= 0, peaks >= 0,
    /// nothing beyond the stack, velocities that agree with the mode, and a
    /// mode that satisfies the contact law.
    pub(super) fn check_restored(&self) -> Result<(), SnapshotError> {
        let n = self.sys.n;
        let finite = [
            self.t,
            self.e_input,
            self.e_viscous,
            self.peak_u0,
            self.peak_a0,
        ]
        .into_iter()
        .chain([self.ag_now, self.fext_now])
        .chain(self.u)
        .chain(self.v)
        .chain(self.e_friction)
        .chain(self.peak_slip)
        .all(f64::is_finite);
        if !finite {
            return Err("a value of the saved state is not finite".into());
        }
        if self.t < 0.0 {
            return Err(format!("time {} of the saved state is negative", self.t));
        }
        if !(self.last_event.is_nan() || (0.0..=self.t).contains(&self.last_event)) {
            return Err(format!(
                "last event time {} of the saved state is not within [0, {}]",
                self.last_event, self.t
            ));
        }
        check_peaks([self.peak_u0, self.peak_a0], &self.peak_slip)?;
        let beyond = (n + 1..MAX_BODIES)
            .any(|i| self.u[i] != 0.0 || self.v[i] != 0.0 || self.e_friction[i] != 0.0)
            || self.peak_slip[n + 1..].iter().any(|&p| p != 0.0);
        if beyond || self.e_friction[0] != 0.0 || self.peak_slip[0] != 0.0 {
            return Err("the saved state has motion beyond its stack".into());
        }
        // A prescribed support drifts from the input frame only by its
        // mobility (mode::support_law); the drift's peak is history: it stays
        // where a mobility has gone back to 0 (every call takes the drift out).
        let support_moves = self.u[0] != 0.0 || self.v[0] != 0.0;
        let drift = support_moves && self.sys.mobility == 0.0;
        if self.sys.prescribed() && (drift || self.e_viscous != 0.0) {
            return Err("the saved state moves a prescribed support relative to itself".into());
        }
        let against = self.against_contact();
        if against != 0 {
            let j = against.trailing_zeros() as usize;
            return Err(format!(
                "interface {j} is {:?} in the saved state but its relative velocity is {}",
                self.mode.contact[j],
                self.v[j] - self.v[j - 1]
            ));
        }
        if !self.mode_is_consistent() {
            return Err("the saved stick/slip mode violates the contact law".into());
        }
        Ok(())
    }
}
