//! An instance's FMU states: get, set, free, and their bytes.
#![forbid(unsafe_code)]

use super::*;

impl<M: Model> Instance<M> {
    /// GetFMUstate: a copy of everything but the name and logger.
    pub fn get_state(&mut self) -> Result<Box<Snapshot<M>>, Status> {
        let f = self.func("GetFMUstate");
        let r = self.allowed(f, self.masks().fmu_state).map(|()| {
            self.trace_state(format_args!("{f}: new snapshot"));
            Box::new(self.core.clone())
        });
        self.edge(r)
    }

    /// GetFMUstate into an existing snapshot, reusing its memory.
    pub fn get_state_into(&mut self, snapshot: &mut Snapshot<M>) -> Status {
        let f = self.func("GetFMUstate");
        let r = self.allowed(f, self.masks().fmu_state).map(|()| {
            snapshot.clone_from(&self.core);
            self.trace_state(format_args!("{f}: into the existing snapshot"));
            Status::Ok
        });
        self.status(r)
    }

    /// SetFMUstate.
    pub fn set_state(&mut self, snapshot: &Snapshot<M>) -> Status {
        let f = self.func("SetFMUstate");
        let r = self.allowed(f, self.masks().fmu_state).and_then(|()| {
            if snapshot.interface != self.core.interface {
                return Err(FmiError::error(format!(
                    "{f}: the FMU state was saved by a {} instance; this one is {}",
                    snapshot.interface.name(),
                    self.core.interface.name()
                )));
            }
            if snapshot.version != self.core.version {
                return Err(FmiError::error(format!(
                    "{f}: the FMU state was saved by an instance of the other FMI version \
                     ({:?}); this one is {:?}: their variables and states differ",
                    snapshot.version, self.core.version
                )));
            }
            self.core.clone_from(snapshot);
            self.trace_state(format_args!("{f}: restored"));
            Ok(Status::Ok)
        });
        self.status(r)
    }

    /// Checks that FreeFMUstate may be called (it may, in every state but fatal). `is_null`:
    /// the host passed a pointer to NULL, so there is nothing to free.
    pub fn check_free_state(&mut self, is_null: bool) -> Status {
        let f = self.func("FreeFMUstate");
        let r = self.allowed(f, mask::ANY_BUT_FATAL).map(|()| {
            let what = if is_null { "NULL, nothing to free" } else { "a snapshot" };
            trace!(self, "{f}: {what}");
            Status::Ok
        });
        self.status(r)
    }

    /// SerializeFMUstate: the byte form of a snapshot ([`snapshot`] documents the format).
    pub fn serialize(&mut self, snapshot: &Snapshot<M>) -> Result<Vec<u8>, Status> {
        let f = self.func("SerializeFMUstate");
        let r = self.allowed(f, self.masks().fmu_state).and_then(|()| {
            let bytes = snapshot::serialize(snapshot).map_err(|e| unwritable(f, e))?;
            trace!(self, "{f}: {} bytes", bytes.len());
            Ok(bytes)
        });
        self.edge(r)
    }

    /// SerializedFMUstateSize.
    pub fn serialized_size(&mut self, snapshot: &Snapshot<M>) -> Result<usize, Status> {
        let f = self.func("SerializedFMUstateSize");
        let r = self.allowed(f, self.masks().fmu_state).and_then(|()| {
            let n = snapshot::serialize(snapshot).map_err(|e| unwritable(f, e))?.len();
            trace!(self, "{f}: {n} bytes");
            Ok(n)
        });
        self.edge(r)
    }

    /// DeSerializeFMUstate: a snapshot from untrusted bytes. Every field is checked;
    /// malformed bytes give an error that says what is wrong.
    pub fn deserialize(&mut self, bytes: &[u8]) -> Result<Box<Snapshot<M>>, Status> {
        let f = self.func("DeSerializeFMUstate");
        let r = self.allowed(f, self.masks().fmu_state).and_then(|()| {
            let core = snapshot::deserialize::<M>(bytes)
                .map(Box::new)
                .map_err(|e| FmiError::error(format!("{f}: {e}")))?;
            let n = bytes.len();
            let state = (f.0.state_name)(core.state);
            trace!(self, "{f}: {n} bytes, a snapshot in state `{state}`");
            Ok(core)
        });
        self.edge(r)
    }
}
