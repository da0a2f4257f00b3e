//! Recordings: a run's byte log re-runs to the same bytes, and a changed byte is found.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use twin::record::{Dir, first_divergence, hash_logs};
use twin::runner::Lockstep;
use twin::setup::RunSetup;

fn logs() -> Vec<twin::record::EndpointLog> {
    let loaded = RunSetup::load(std::path::Path::new("../scenarios/lossy-motor.ron")).unwrap();
    let mut run = Lockstep::new(loaded, None).unwrap();
    run.run_to_end(|_| {});
    run.link_logs().to_vec()
}

#[test]
fn a_replay_matches_the_recording_and_a_changed_byte_is_located() {
    let recorded = logs();
    let replayed = logs();
    assert_eq!(first_divergence(&recorded, &replayed), None);
    assert_eq!(hash_logs(&recorded), hash_logs(&replayed));
    // Every link and endpoint is recorded.
    for (link, endpoint) in
        [("motor", "carto"), ("motor", "board"), ("sensor", "carto"), ("sensor", "board"), ("gui", "cute#1")]
    {
        assert!(
            recorded.iter().any(|l| l.link == link && l.endpoint == endpoint && !l.chunks.is_empty()),
            "{link}@{endpoint}"
        );
    }

    // Flip one byte Carto wrote to the motor board, 10 bytes into its 100th write.
    let mut tampered = recorded.clone();
    let log = tampered.iter_mut().find(|l| l.link == "motor" && l.endpoint == "carto").unwrap();
    let writes: Vec<usize> =
        (0..log.chunks.len()).filter(|&i| log.chunks[i].direction == Dir::Written).collect();
    let chunk = writes[99];
    let offset: usize = writes[..99].iter().map(|&i| log.chunks[i].bytes.len()).sum::<usize>();
    let at = 10.min(log.chunks[chunk].bytes.len() - 1);
    log.chunks[chunk].bytes[at] ^= 0x01;
    let d = first_divergence(&recorded, &tampered).expect("a divergence");
    assert_eq!(d.endpoint, "motor@carto");
    assert_eq!(d.dir, Dir::Written);
    assert_eq!(d.offset, (offset + at) as u64);
}
