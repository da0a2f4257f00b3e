#!/usr/bin/env bash
# Writes the session target's seed corpus into corpus/session/: recorded lockstep runs (a STOP
# mid-trajectory, a reconnect, a lossy motor link, a GoTo) turned into fuzz inputs by the test
# tests/tests/carto_fuzz_seeds.rs, which also checks that every seed holds the property.
# corpus/ is git-ignored: run this before fuzzing.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
cd "$here/../.."
EXPLOBOT_FUZZ_SEEDS="$here/corpus/session" \
  cargo test --release -p explobot-tests --test carto_fuzz_seeds -- --nocapture
echo "seed corpus written: $(find "$here/corpus/session" -type f | wc -l) files"
