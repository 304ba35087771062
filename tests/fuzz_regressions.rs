//! The inputs in `fuzz/regressions/deserialize/` once made fmi2DeSerializeFMUstate accept bytes
//! that it then dropped on the way (see the file names). `cargo xtask fuzz` replays them through
//! the fuzz target; this test replays them without a fuzz build, so `cargo test` catches a
//! regression too. Each file is the target's input: a mode byte (odd: reseal the frame, as the
//! target does), then a serialized state.

use beam_body::fmi2::instance::{Instance, Status, FMI2_COSIMULATION};
use beam_body::fmi2::variables::guid;
use std::cell::RefCell;
use std::rc::Rc;

/// Bytes of the frame before the payload: magic 8, version 4, GUID 38, length 8.
const HEADER: usize = 8 + 4 + 38 + 8;

fn fnv1a_64(bytes: &[u8]) -> u64 {
    bytes
        .iter()
        .fold(0xcbf2_9ce4_8422_2325, |h, &b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3))
}

/// The payload length and the checksum made consistent with the bytes.
fn reseal(bytes: &mut [u8]) {
    let payload = (bytes.len() - HEADER - 8) as u64;
    bytes[HEADER - 8..HEADER].copy_from_slice(&payload.to_le_bytes());
    let n = bytes.len() - 8;
    let sum = fnv1a_64(&bytes[..n]);
    bytes[n..].copy_from_slice(&sum.to_le_bytes());
}

#[test]
fn deserializer_regressions_are_refused_with_their_reason() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/regressions/deserialize");
    // (file, the reason the reader must give)
    let expected = [
        ("lu-factors-without-an-lu", "absent `lu`"),
        ("tolerance-value-without-its-flag", "`tolerance_defined` is 0"),
        ("unused-reals-of-the-law-piece", "uses only"),
    ];
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).expect("fuzz/regressions/deserialize") {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let (_, reason) = expected
            .iter()
            .find(|(file, _)| *file == name)
            .unwrap_or_else(|| panic!("{name}: add it to this test with its reason"));
        let input = std::fs::read(&path).unwrap();
        let (mode, rest) = input.split_first().expect("a mode byte");
        let mut bytes = rest.to_vec();
        if mode % 2 == 1 {
            reseal(&mut bytes);
        }
        let log: Rc<RefCell<Vec<String>>> = Rc::default();
        let sink = log.clone();
        let logger = Box::new(move |_: Status, _: &str, m: &str| sink.borrow_mut().push(m.into()));
        let mut inst =
            Instance::instantiate("regression", FMI2_COSIMULATION, guid(), logger, false)
                .expect("instantiate");
        assert_eq!(inst.deserialize(&bytes).err(), Some(Status::Error), "{name} was accepted");
        let log = log.borrow();
        assert!(log.iter().any(|m| m.contains(reason)), "{name}: {log:?}");
        seen += 1;
    }
    assert_eq!(seen, expected.len());
}
