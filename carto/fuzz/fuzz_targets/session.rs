//! The whole daemon, not only its decoders (issue 45): Carto's sans-IO runtime over in-memory
//! links, driven by an arbitrary interleaving of client bytes, motor-board bytes, sensor-board
//! bytes, reconnects, link losses and time steps. Input format and checks:
//! [`carto::fuzzing`] (no panic, bounded buffers, no drive other than zero after a STOP or a lost
//! client until the next move).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(violation) = carto::fuzzing::run(data) {
        panic!("{violation}");
    }
});
