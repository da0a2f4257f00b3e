use clap::Parser as _;

use super::*;

/// `explobot encode WORDS…`, parsed and encoded as the CLI does.
fn encode(words: &[&str]) -> Result<Vec<u8>, String> {
    let args = EncodeArgs::try_parse_from(std::iter::once("encode").chain(words.iter().copied()))
        .map_err(|e| e.to_string())?;
    args.encode().map_err(|e| e.to_string())
}

#[test]
fn decode_reports_resync_and_checksum_verdicts() {
    // Garbage, a frame with a bad checksum, then the seed's frame.
    let out =
        decode_hex(Protocol::Motor, "11 22 AA 03 01 80 80 06 0B AA 03 01 80 80 06 0A", ChecksumPolicy::Sum)
            .unwrap();
    assert!(out.contains("bad checksum"), "{out}");
    assert!(out.contains("skipped"), "{out}");
    assert!(out.contains("dir_x: 128, dir_y: 128, gear: 6"), "{out}");
    assert!(out.trim_end().ends_with("1 frame(s), 1 error(s), 9 bytes skipped"), "{out}");
    assert!(out.find("bad checksum") < out.find("resync"), "{out}");
    // With the firmware's "ignore" policy the first frame is accepted too.
    let out = decode_hex(Protocol::Motor, "AA 03 01 80 80 06 0B", ChecksumPolicy::Ignore).unwrap();
    assert!(out.contains("1 frame(s), 0 error(s)"), "{out}");
}

#[test]
fn decode_link_says_which_byte_order_and_flags_fatal_sizes() {
    let out = decode_hex(Protocol::Link, "00 05 00 07 02 03 03", ChecksumPolicy::Sum).unwrap();
    assert!(out.contains("LittleEndian"), "{out}");
    let out = decode_hex(Protocol::Link, "00 00 01 02", ChecksumPolicy::Sum).unwrap();
    assert!(out.contains("fatal"), "{out}");
}

#[test]
fn encode_builds_the_spec_frames() {
    assert_eq!(
        encode(&["--protocol", "motor", "drive-v1", "0x80", "0x80", "6"]).unwrap(),
        parse_hex("AA 03 01 80 80 06 0A").unwrap()
    );
    assert_eq!(
        encode(&["--protocol", "motor", "drive-v2", "50", "0", "-20", "6"]).unwrap(),
        parse_hex("AA 06 10 32 00 EC 06 00 00 3A").unwrap()
    );
    assert_eq!(
        encode(&["--protocol", "link", "--little-endian", "stop"]).unwrap(),
        parse_hex("00 02 00 06").unwrap()
    );
    assert_eq!(
        encode(&["--protocol", "sensor", "distance", "1", "123.25"]).unwrap(),
        parse_hex("03 08 04 01 01 04 42 F6 80 00").unwrap()
    );
    assert_eq!(
        encode(&["--protocol", "sensor", "keep-state", "2", "258"]).unwrap(),
        parse_hex("01 03 02 01 02").unwrap()
    );
}

#[test]
fn the_argument_definitions_pass_clap_debug_asserts() {
    use clap::CommandFactory as _;
    EncodeArgs::command().debug_assert();
    DecodeArgs::command().debug_assert();
}

#[test]
fn every_message_encodes_a_frame_that_decodes_cleanly() {
    let lines: [&[&str]; 19] = [
        &["link", "trajectory", "6", "right"],
        &["link", "cartography", "0x02"],
        &["link", "move-done"],
        &["link", "obstacle", "2", "4"],
        &["link", "robot", "2", "4"],
        &["link", "stop"],
        &["link", "position", "2", "3", "east"],
        &["link", "position-received"],
        &["motor", "drive-v1", "1", "2", "3"],
        &["motor", "drive-v2", "-128", "127", "0x7F"],
        &["motor", "telemetry", "100", "-100", "50.5", "0", "25", "-25", "12.5", "0"],
        &["motor", "telemetry36", "1", "2", "3", "4", "5", "6", "7", "-8e3"],
        &["sensor", "keep-state", "1", "1"],
        &["sensor", "command", "1", "-5"],
        &["sensor", "distance", "1", "-1"],
        &["sensor", "encoder", "2", "-2", "reverse"],
        &["sensor", "switch", "4", "pressed"],
        &["sensor", "pot", "3", "45.5"],
        &["sensor", "navx", "7", "1.5", "1013.25", "90", "20.25", "0.5", "-0.5", "9.81", "12", "-3"],
    ];
    for line in lines {
        let (protocol, message) = line.split_first().unwrap();
        let words: Vec<&str> = ["--protocol", protocol].into_iter().chain(message.iter().copied()).collect();
        let bytes = encode(&words).unwrap_or_else(|e| panic!("{line:?}: {e}"));
        let protocol = <Protocol as clap::ValueEnum>::from_str(protocol, false).unwrap();
        let out = decode_bytes(protocol, &bytes, ChecksumPolicy::Sum);
        let summary = out.lines().last().unwrap_or_default();
        assert!(summary.starts_with("1 frame(s), 0 error(s)"), "{line:?}: {out}");
    }
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    assert!(parse_hex("A").is_err());
    assert!(parse_hex("zz").is_err());
    assert!(encode(&["--protocol", "link", "trajectory", "300", "forward"]).is_err());
    assert!(encode(&["--protocol", "motor", "drive-v2", "1"]).is_err());
    assert!(encode(&["--protocol", "sensor", "warp"]).is_err());
    assert!(encode(&["--protocol", "link"]).is_err());
    assert_eq!(
        encode(&["--protocol", "link", "drive-v1", "1", "2", "3"]),
        Err("that is a motor message, but --protocol is link".to_owned())
    );
}
