#!/usr/bin/env bash
# Writes the seed corpus (the golden frames of protocols-research.md §1.6-1.7, §2.8, §3.5 and the
# seed's motor example) into corpus/<target>/. Each input starts with the control byte the targets
# read first (chunk size; for motor also the checksum policy in the top 2 bits: 00 = sum).
# corpus/ is git-ignored: run this before `cargo fuzz run`.
set -euo pipefail
cd "$(dirname "$0")"

seed() { # target name hex-bytes...
  local target=$1 name=$2; shift 2
  mkdir -p "corpus/$target"
  local escaped=""
  for byte in "$@"; do escaped+="\\x$byte"; done
  printf "$escaped" > "corpus/$target/$name"
}

# link: control byte 03, then frames.
seed link_decoder observed_send_robot_position_le 03 00 05 00 07 02 03 03
seed link_decoder observed_session 03 00 02 08 00 00 04 05 00 02 04 00 02 03 00 00 04 04 00 02 04
seed link_decoder observed_cartography_le 03 00 03 00 02 00 00 03 00 02 02
seed link_decoder observed_trajectory_le 03 00 04 00 01 06 00 00 04 00 01 06 01 00 02 00 06
seed link_decoder doc_frames 05 00 04 01 00 03 02 00 03 02 00 00 00 04 04 00 09 15 00 04 05 00 21 02 00 02 06 00 00 05 07 00 17 14 00
seed link_decoder cute_2024_size_2 01 00 02 02 00 00 03 02 00 00

# motor: control byte 04 (sum policy, chunks of 4), then frames.
seed motor_decoder seed_drive_v1 04 AA 03 01 80 80 06 0A
seed motor_decoder drive_v2 04 AA 06 10 32 00 EC 06 00 00 3A AA 06 10 00 00 00 00 00 00 16
seed motor_decoder telemetry_32 07 AA 20 04 00 00 C8 42 00 00 C8 C2 00 00 4A 42 00 00 00 00 00 00 C8 41 00 00 C8 C1 00 00 48 41 00 00 00 00 5F
seed motor_decoder telemetry_36 07 AA 24 04 01 00 00 00 00 00 C8 42 00 00 C8 C2 00 00 4A 42 00 00 00 00 00 00 C8 41 00 00 C8 C1 00 00 48 41 00 00 00 00 64
seed motor_decoder telemetry_36_xor_ignore C7 AA 24 04 01 00 00 00 00 00 C8 42 00 00 C8 C2 00 00 4A 42 00 00 00 00 00 00 C8 41 00 00 C8 C1 00 00 48 41 00 00 00 00 00
seed motor_decoder hidden_in_false_start 05 AA 10 AA 03 01 80 80 06 0A 00 00 00 00 00 00 00 00 00 00 00

# sensor: control byte 03, then frames.
seed sensor_decoder keep_state 03 01 03 02 01 02 01 03 01 00 01
seed sensor_decoder command 03 02 03 05 03 E8
seed sensor_decoder navx 03 03 28 01 07 01 24 3F C0 00 00 44 7D 50 00 42 B4 00 00 41 A2 00 00 3F 00 00 00 BF 00 00 00 41 1C F5 C3 41 40 00 00 C0 40 00 00
seed sensor_decoder encoder 03 03 09 02 02 01 05 FF FF FF FE 01
seed sensor_decoder potentiometer_distance 03 03 08 03 03 01 04 42 36 00 00 03 08 04 01 01 04 42 F6 80 00
seed sensor_decoder switch_after_garbage 02 F0 F1 03 05 05 04 01 01 02

echo "seed corpus written: $(find corpus -type f | wc -l) files"
