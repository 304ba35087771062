//! fmi2DeSerializeFMUstate on arbitrary bytes. Rejected bytes must give fmi2Error with a
//! logged reason; accepted bytes must be canonical (they serialize back unchanged) and must
//! restore an instance that steps and reports finite values.
//!
//! The first byte picks the mode: odd, the rest is resealed first (payload length and
//! checksum made consistent, `beam_body_fuzz::reseal`), which lets mutations reach the
//! checks of every field; even, the rest is passed as it is, which tests the frame.
#![no_main]

use beam_body::fmi::{State, Status, Version, STATUS_LAST_SUCCESSFUL_TIME};
use beam_body_fuzz::{check_outputs, check_status, instance, instance3, instance_of, reseal};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|input: &[u8]| {
    let Some((&mode, rest)) = input.split_first() else {
        return;
    };
    let mut bytes = rest.to_vec();
    if mode % 2 == 1 {
        reseal(&mut bytes);
    }
    let data = &bytes[..];
    let (mut inst, records) = instance(false);
    let core = match inst.deserialize(data) {
        Ok(core) => core,
        Err(status) => {
            check_status("fmi2DeSerializeFMUstate", status, &records, 0);
            assert_eq!(status, Status::Error);
            return;
        }
    };
    let again = inst.serialize(&core).expect("an accepted state serializes");
    if again != data {
        let at = again.iter().zip(data).position(|(a, b)| a != b).unwrap_or(again.len());
        let show = |b: &[u8]| b[at.min(b.len())..(at + 16).min(b.len())].to_vec();
        panic!(
            "accepted bytes are not canonical: {} bytes in, {} back, first difference at {at}: \
             {:?} in, {:?} back",
            data.len(),
            again.len(),
            show(data),
            show(&again)
        );
    }
    // A state restores into an instance of its own interface and FMI version.
    let (mut inst, records) = match core.version() {
        Version::Fmi2 => instance_of(core.interface(), false),
        Version::Fmi3 => instance3(core.interface()),
    };
    assert_eq!(inst.set_state(&core), Status::Ok);
    check_outputs(&mut inst, &records);
    // Model Exchange: the derivatives are finite or refused with a reason, and a completed
    // step ends cleanly.
    if inst.state() == State::ContinuousTimeMode {
        let before = records.borrow().len();
        // FMI 2.0's six states, or FMI 3.0's 4·n_elements + 2.
        let mut dx = vec![0.0; inst.number_of_continuous_states().unwrap_or(6)];
        let status = inst.get_derivatives(&mut dx);
        let name = match inst.api().prefix {
            "fmi3" => "fmi3GetContinuousStateDerivatives",
            _ => "fmi2GetDerivatives",
        };
        check_status(name, status, &records, before);
        if status == Status::Ok {
            assert!(dx.iter().all(|x| x.is_finite()), "non-finite derivatives {dx:?}");
        }
        let before = records.borrow().len();
        let status = inst.completed_integrator_step().err().unwrap_or(Status::Ok);
        let name = format!("{}CompletedIntegratorStep", inst.api().prefix);
        check_status(&name, status, &records, before);
    }
    // Step on from the restored state: whatever it holds, the step must end cleanly.
    if inst.state() == State::StepComplete {
        let tc = inst.get_real_status(STATUS_LAST_SUCCESSFUL_TIME).expect("allowed");
        let before = records.borrow().len();
        let status = inst.do_step(tc, 0.01);
        check_status(&format!("{}DoStep", inst.api().prefix), status, &records, before);
        check_outputs(&mut inst, &records);
    }
});
