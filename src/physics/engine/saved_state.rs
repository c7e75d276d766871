//! The simulator's dynamic state as bytes (the FMU's saved states).

use super::*;

impl Simulator {
    /// Writes the whole dynamic state (and the scene it belongs to).
    pub fn write_state(&self, w: &mut ByteWriter) {
        self.params.write(w);
        w.u8(match self.settings.method {
            Method::EventLocated => 1,
            Method::StepEnd => 2,
        });
        w.f64(self.settings.max_step);
        w.f64(self.t);
        w.f64s(&self.u);
        w.f64s(&self.v);
        w.f64s(&[self.e_input, self.e_viscous]);
        w.f64s(&self.e_friction);
        for c in self.mode.contact {
            w.u8(match c {
                Contact::Stuck => 0,
                Contact::SlipForward => 1,
                Contact::SlipBackward => 2,
                Contact::Free => 3,
            });
        }
        w.f64(self.peak_u0);
        w.f64s(&self.peak_slip);
        w.f64s(&[self.peak_a0, self.ag_now, self.fext_now, self.last_event]);
        let s = &self.stats;
        for x in [s.steps, s.events, s.inconsistent, s.muted, s.ambiguous] {
            w.u64(x);
        }
        w.f64(self.sys.mobility);
        w.f64s(&[self.sys.ref_mass, self.sys.ref_load]);
    }

    /// Reads a state written by [`Simulator::write_state`].
    pub fn read_state(r: &mut ByteReader) -> Result<Simulator, SnapshotError> {
        let p = Params::read(r)?;
        let method = match r.u8()? {
            1 => Method::EventLocated,
            2 => Method::StepEnd,
            m => return Err(format!("unknown solver {m} in the saved state")),
        };
        let settings = Settings {
            method,
            max_step: r.f64()?,
        };
        let mut sim = Simulator::new(&p, &settings).map_err(|e| e.to_string())?;
        sim.t = r.f64()?;
        r.f64s(&mut sim.u)?;
        r.f64s(&mut sim.v)?;
        sim.e_input = r.f64()?;
        sim.e_viscous = r.f64()?;
        r.f64s(&mut sim.e_friction)?;
        for c in sim.mode.contact.iter_mut() {
            *c = match r.u8()? {
                0 => Contact::Stuck,
                1 => Contact::SlipForward,
                2 => Contact::SlipBackward,
                3 => Contact::Free,
                x => return Err(format!("unknown contact state {x} in the saved state")),
            };
        }
        sim.check_restored_contacts()?;
        sim.peak_u0 = r.f64()?;
        r.f64s(&mut sim.peak_slip)?;
        let mut tail = [0.0; 4];
        r.f64s(&mut tail)?;
        [sim.peak_a0, sim.ag_now, sim.fext_now, sim.last_event] = tail;
        sim.stats = Stats {
            steps: r.u64()?,
            events: r.u64()?,
            inconsistent: r.u64()?,
            muted: r.u64()?,
            ambiguous: r.u64()?,
        };
        let mobility = r.f64()?;
        sim.set_support_mobility(mobility)
            .map_err(|e| format!("in the saved state: {e}"))?;
        let mut reference = [0.0; 2];
        r.f64s(&mut reference)?;
        if !reference.iter().all(|x| x.is_finite()) {
            return Err("the saved state's reference mode is not finite".into());
        }
        [sim.sys.ref_mass, sim.sys.ref_load] = reference;
        sim.rebuild_dynamics();
        sim.check_restored()?;
        Ok(sim)
    }
}
