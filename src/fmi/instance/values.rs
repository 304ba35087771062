//! An instance's get and set by value reference: the lookups, the checks of each value
//! against its variable and the state, all-or-none sets, and the base types the model has no
//! variables of.
#![forbid(unsafe_code)]

use super::*;

impl<M: Model> Instance<M> {
    /// Finds `vr` and checks it has base type `base`.
    #[inline]
    pub(crate) fn lookup(func: Func, vr: u32, base: BaseType) -> FmiResult<&'static VarInfo> {
        let version = func.version();
        match M::variable(vr) {
            Some(info) if !info.in_version(version) => Err(FmiError::error(format!(
                "{func}: value reference {vr} (`{}`) is not in this version's model \
                 description: it is FMI {}'s only",
                info.name,
                if info.only == Only::Fmi2 { "2.0" } else { "3.0" }
            ))),
            Some(info) if base == info.base_in(version) => Ok(info),
            found => Err(bad_reference(func, vr, base, found, M::variable_count())),
        }
    }

    /// The value of any variable of base type `base`.
    fn get_value(&mut self, func: Func, vr: u32, base: BaseType) -> FmiResult<Value> {
        let info = Self::lookup(func, vr, base)?;
        if info.causality == Causality::Independent {
            return Ok(Value::Real(self.core.time));
        }
        let setup = self.core.setup;
        let value = self.core.model.get(vr, &setup).map_err(|msg| {
            FmiError::error(format!("{func}: the outputs cannot be computed: {msg}"))
        })?;
        match value {
            Value::Real(x)
                if !x.is_finite()
                    && matches!(info.causality, Causality::Output | Causality::Local) =>
            {
                Err(FmiError::error(format!(
                    "{func}: output `{}` is not finite at t = {}",
                    info.name, self.core.time
                )))
            }
            _ => Ok(value),
        }
    }

    /// The number of values of `info`: 1 for a scalar, the product of its dimensions for an
    /// FMI 3.0 array, at the structural parameters' current values.
    fn len_of(&mut self, info: &VarInfo) -> usize {
        let setup = self.core.setup;
        info.dims.iter().fold(1, |n, d| {
            n * match *d {
                Dim::Fixed(k) => k as usize,
                Dim::Param(vr) => match self.core.model.get(vr, &setup) {
                    Ok(Value::Integer(k)) => k.max(0) as usize,
                    _ => 0,
                },
            }
        })
    }

    /// Checks `vrs` against base type `base` and returns how many values each has; Error
    /// when they do not add up to the host's `n` (`nValues` in FMI 3.0).
    fn sizes(&mut self, f: Func, base: BaseType, vrs: &[u32], n: usize) -> FmiResult<Vec<usize>> {
        let mut sizes = Vec::with_capacity(vrs.len());
        for vr in vrs {
            let info = Self::lookup(f, *vr, base)?;
            if !info.dims.is_empty() && base != BaseType::Real {
                // Every array is a Float64 ([`Model::get_array`]).
                return Err(bad_reference(f, *vr, base, Some(info), M::variable_count()));
            }
            sizes.push(self.len_of(info));
        }
        let total: usize = sizes.iter().sum();
        if total == n {
            return Ok(sizes);
        }
        let arrays: Vec<String> = vrs
            .iter()
            .zip(&sizes)
            .filter_map(|(vr, k)| {
                let info = M::variable(*vr)?;
                (!info.dims.is_empty()).then(|| format!("`{}` has {k}", info.name))
            })
            .collect();
        Err(FmiError::error(if arrays.is_empty() {
            format!("{f}: {} value references but {n} values", vrs.len())
        } else {
            format!(
                "{f}: nValues = {n}, but the {} value references name {total} values (an array \
                 counts its elements: {})",
                vrs.len(),
                arrays.join(", ")
            )
        }))
    }

    /// The values of array variable `vr` (FMI 3.0) into `out`.
    fn get_array(&mut self, f: Func, vr: u32, out: &mut [f64]) -> FmiResult<()> {
        let setup = self.core.setup;
        self.core.model.get_array(vr, &setup, out).map_err(|msg| {
            FmiError::error(format!("{f}: the outputs cannot be computed: {msg}"))
        })?;
        if let Some(k) = out.iter().position(|x| !x.is_finite()) {
            let name = M::variable(vr).map_or("?", |v| v.name);
            return Err(FmiError::error(format!(
                "{f}: `{name}`[{k}] is not finite at t = {}",
                self.core.time
            )));
        }
        Ok(())
    }

    /// Gets every value of `vrs` of base type `base` into `out`: one for each scalar, all
    /// the elements of each array (FMI 3.0), row-major.
    pub fn get<T: fmt::Debug>(
        &mut self,
        name: &'static str,
        base: BaseType,
        vrs: &[u32],
        out: &mut [T],
        convert: impl Fn(Value) -> T,
    ) -> Status {
        let f = self.func(name);
        let r = (|| {
            self.allowed(f, self.masks().get)?;
            // Scalars only (every FMI 2.0 call, most FMI 3.0 ones): one value each, no sizes.
            if vrs.iter().all(|vr| M::variable(*vr).is_none_or(|v| v.dims.is_empty())) {
                if vrs.len() != out.len() {
                    return Err(FmiError::error(format!(
                        "{f}: {} value references but {} values",
                        vrs.len(),
                        out.len()
                    )));
                }
                for (vr, slot) in vrs.iter().zip(out.iter_mut()) {
                    *slot = convert(self.get_value(f, *vr, base)?);
                }
                trace!(self, "{f}: {}", listing::<M, T>(vrs, out));
                return Ok(Status::Ok);
            }
            let sizes = self.sizes(f, base, vrs, out.len())?;
            let mut k = 0;
            let mut array = Vec::new();
            for (vr, &n) in vrs.iter().zip(&sizes) {
                let info = Self::lookup(f, *vr, base)?;
                if info.dims.is_empty() {
                    out[k] = convert(self.get_value(f, *vr, base)?);
                } else {
                    array.resize(n, 0.0);
                    self.get_array(f, *vr, &mut array)?;
                    for (slot, x) in out[k..k + n].iter_mut().zip(&array) {
                        *slot = convert(Value::Real(*x));
                    }
                }
                k += n;
            }
            let listed = Listing::<M, T>(vrs, out, Some(&sizes), std::marker::PhantomData);
            trace!(self, "{f}: {listed}");
            Ok(Status::Ok)
        })();
        self.status(r)
    }

    /// The get and set functions of a type the model has no variable of (strings, and
    /// FMI 3.0's Float32, Int8, …): any value reference is refused, naming its variable's type.
    pub fn no_variables(
        &mut self,
        name: &'static str,
        base: BaseType,
        set: bool,
        vrs: &[u32],
    ) -> Status {
        let f = self.func(name);
        let allowed = if set { self.masks().set } else { self.masks().get };
        let r = self.allowed(f, allowed).and_then(|()| match vrs.first() {
            None => {
                trace!(self, "{f}: no variables");
                Ok(Status::Ok)
            }
            Some(vr) => Self::lookup(f, *vr, base).map(|_| Status::Error),
        });
        self.status(r)
    }

    /// Sets all values or none: each is checked first, against its variable's causality,
    /// the current state and its range; then all are set. One value, what a host sends for
    /// its inputs at every communication point, goes the short way with the same checks.
    pub fn set<T: Copy + fmt::Debug>(
        &mut self,
        name: &'static str,
        base: BaseType,
        vrs: &[u32],
        values: &[T],
        convert: impl Fn(T) -> Value,
    ) -> Status {
        let f = self.func(name);
        let r = match (vrs, values) {
            ([vr], [value]) => self.set_one(f, base, *vr, *value, convert),
            _ => self.set_all(f, base, vrs, values, convert),
        };
        self.status(r)
    }

    /// [`set`](Self::set) of one value.
    #[inline]
    fn set_one<T: Copy + fmt::Debug>(
        &mut self,
        f: Func,
        base: BaseType,
        vr: u32,
        value: T,
        convert: impl Fn(T) -> Value,
    ) -> FmiResult {
        self.allowed(f, self.masks().set)?;
        let state = self.core.state;
        let info = Self::lookup(f, vr, base)?;
        self.settable(f, vr, info, state)?;
        let mut notes = Notes::new();
        let set = self.core.model.set(vr, convert(value), state, &mut notes);
        set.map_err(|msg| FmiError::error(format!("{f}: {msg}")))?;
        self.intermediate_set |= state == State::IntermediateUpdate;
        trace!(self, "{f}: {}", listing::<M, T>(&[vr], &[value]));
        Ok(self.notes(f, notes))
    }

    /// [`set`](Self::set) of several values, all or none.
    fn set_all<T: Copy + fmt::Debug>(
        &mut self,
        f: Func,
        base: BaseType,
        vrs: &[u32],
        values: &[T],
        convert: impl Fn(T) -> Value,
    ) -> FmiResult {
        self.allowed(f, self.masks().set)?;
        let state = self.core.state;
        for vr in vrs {
            let info = Self::lookup(f, *vr, base)?;
            self.settable(f, *vr, info, state)?;
        }
        // Arrays are never settable, so each value reference has one value.
        self.sizes(f, base, vrs, values.len())?;
        for (vr, value) in vrs.iter().zip(values) {
            // All or none: each value is checked before any is set.
            let checked = self.core.model.check(*vr, convert(*value));
            checked.map_err(|msg| FmiError::error(format!("{f}: {msg}")))?;
        }
        let mut notes = Notes::new();
        for (vr, value) in vrs.iter().zip(values) {
            let set = self.core.model.set(*vr, convert(*value), state, &mut notes);
            set.map_err(|msg| FmiError::error(format!("{f}: {msg}")))?;
        }
        self.intermediate_set |= state == State::IntermediateUpdate && !vrs.is_empty();
        trace!(self, "{f}: {}", listing::<M, T>(vrs, values));
        Ok(self.notes(f, notes))
    }

    /// Whether `info` may be set in `state`: not an output, a fixed parameter only
    /// before initialization ends, in intermediate update mode an intermediate input only.
    #[inline]
    fn settable(&self, f: Func, vr: u32, info: &VarInfo, state: State) -> FmiResult<()> {
        let running = self.masks().running & state.bit() != 0;
        if state == State::IntermediateUpdate && !M::intermediate_input(vr) {
            let inputs: Vec<String> = (0..M::variable_count() as u32)
                .filter(|k| M::intermediate_input(*k))
                .filter_map(|k| M::variable(k).map(|v| format!("`{}`", v.name)))
                .collect();
            return Err(FmiError::error(format!(
                "{f}: cannot set `{}` in intermediate update mode: only the inputs with \
                 intermediateUpdate = true ({}) may be set there",
                info.name,
                inputs.join(", ")
            )));
        }
        if f.0.configuration_mode && info.structural != (state == State::ConfigurationMode) {
            return Err(FmiError::error(if info.structural {
                format!(
                    "{f}: cannot set `{}` in `{}`: it is a structural parameter, set only in \
                     configuration mode ({}EnterConfigurationMode after instantiation)",
                    info.name,
                    (f.0.state_name)(state),
                    f.0.prefix
                )
            } else {
                format!(
                    "{f}: cannot set `{}` in configuration mode: only the structural parameters \
                     may be set there",
                    info.name
                )
            }));
        }
        match info.causality {
            Causality::Output | Causality::Local | Causality::Independent => {
                Err(self.refusal(f, info, state))
            }
            Causality::Parameter if running => Err(self.refusal(f, info, state)),
            _ => Ok(()),
        }
    }

    /// Why `info` cannot be set in `state` (see [`settable`](Self::settable)).
    #[cold]
    #[inline(never)]
    fn refusal(&self, f: Func, info: &VarInfo, state: State) -> FmiError {
        let why = match info.causality {
            Causality::Output => "it is an output".to_string(),
            Causality::Local => "it is a calculated local variable".to_string(),
            Causality::Independent => "it is the independent variable, the host's time".into(),
            _ => format!(
                "it is a fixed parameter, settable only before {} (state is `{}`)",
                self.func("ExitInitializationMode"),
                (f.0.state_name)(state)
            ),
        };
        FmiError::error(format!("{f}: cannot set `{}`: {why}", info.name))
    }

    /// GetReal.
    pub fn get_real(&mut self, vrs: &[u32], out: &mut [f64]) -> Status {
        self.get("GetReal", BaseType::Real, vrs, out, Value::real)
    }

    /// GetInteger (integers and enumerations).
    pub fn get_integer(&mut self, vrs: &[u32], out: &mut [i32]) -> Status {
        // The model's integers are its settings', within their Int32 ranges.
        self.get("GetInteger", BaseType::Integer, vrs, out, |v| v.integer() as i32)
    }

    /// GetBoolean.
    pub fn get_boolean(&mut self, vrs: &[u32], out: &mut [bool]) -> Status {
        self.get("GetBoolean", BaseType::Boolean, vrs, out, Value::boolean)
    }

    /// GetString, for a model without string variables.
    pub fn get_string(&mut self, vrs: &[u32]) -> Status {
        self.no_variables("GetString", BaseType::String, false, vrs)
    }

    /// SetReal.
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Status {
        self.set("SetReal", BaseType::Real, vrs, values, Value::Real)
    }

    /// SetInteger (integers and enumerations).
    pub fn set_integer(&mut self, vrs: &[u32], values: &[i32]) -> Status {
        self.set("SetInteger", BaseType::Integer, vrs, values, |k: i32| Value::Integer(k.into()))
    }

    /// SetBoolean.
    pub fn set_boolean(&mut self, vrs: &[u32], values: &[bool]) -> Status {
        self.set("SetBoolean", BaseType::Boolean, vrs, values, Value::Boolean)
    }

    /// SetString, for a model without string variables.
    pub fn set_string(&mut self, vrs: &[u32]) -> Status {
        self.no_variables("SetString", BaseType::String, true, vrs)
    }
}
