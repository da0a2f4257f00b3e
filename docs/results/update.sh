#!/usr/bin/env bash
# docs/results/update.sh: the figures the README quotes, generated, never pasted.
#
#   bash docs/results/update.sh            build explobot, run the sweeps below, write
#                                          docs/results/<name>/{summary.md,STAMP} and
#                                          docs/results/compare-known-room.md, then rewrite the
#                                          README's status box
#   bash docs/results/update.sh --only NAME
#                                          re-run the one sweep NAME (a change that moves only
#                                          its figures), then the comparison and the status box
#   bash docs/results/update.sh --status   only rewrite the README's status box from the files
#                                          present in docs/results/
#   bash docs/results/update.sh --check    only check that the README's status box is what
#                                          --status would write (exit 1 and a diff if not);
#                                          tests/tests/readme.rs runs this in CI
#   EXPLOBOT=path/to/explobot bash docs/results/update.sh
#                                          use that binary instead of building one (its STAMP
#                                          then says the binary was not built from the commit)
#
# Each sweep's folder keeps summary.md (its first line is the verdict the status box quotes) and
# STAMP (commit, date, machine, command); the two generated baselines keep results.jsonl too, so
# that a later change can be paired with them run by run (`explobot sweep compare`). junit.xml
# and sweep.json are deleted: `explobot sweep` writes them again from the same command.
# Documented in docs/how-to/sweeps.md.
set -euo pipefail
cd "$(dirname "$0")/../.."

RESULTS=docs/results
README=README.md
BEGIN='<!-- status:begin -->'
END='<!-- status:end -->'
GENERATED='--generate flat:40 --generate office:40 --generate warehouse:40 --generate pillars:40 --generate irregular:40'

# name | what the status box calls it | the sweep's arguments (before --out)
SWEEPS=(
  "generated-600|realistic generated rooms (flat, office, warehouse, pillars, irregular; 40 each) × run seeds 1–3|$GENERATED --seeds 1..3"
  "generated-600-known-room|the same rooms with Carto given every surface beforehand (\`--known-room\`: an analysis, not the robot's result)|$GENERATED --seeds 1..3 --known-room"
  "scenarios-240|the 12 hand-drawn scenarios (0.30 m cells, margins) × seeds 1–20|scenarios/*.ron --seeds 1..20"
  "measured-240|the 12 scenarios redrawn as measured (\`scenarios/measured/\`) × seeds 1–20|scenarios/measured/*.ron --seeds 1..20"
)

# History shown when docs/results/ holds no summary yet: file | what it was.
HISTORY=(
  "docs/journal/figures/generated-200-cells-0.45.md|realistic generated rooms, 200, one seed per room"
  "docs/journal/figures/generated-200-known-room.md|the same with \`--known-room\` (analysis)"
  "docs/journal/figures/scenarios-seeds-1-20.md|the 12 hand-drawn scenarios × seeds 1–20"
  "docs/journal/figures/measured-seeds-1-20.md|the 12 scenarios redrawn as measured × seeds 1–20"
)

# The first Markdown heading of a file, without its '#'s.
heading() {
  sed -n 's/^#\{1,6\} \{1,\}//p' "$1" | head -n 1
}

# One field of a STAMP file ("key: value" lines).
stamp_field() {
  sed -n "s/^$2: //p" "$1" | head -n 1
}

# The status box's lines, between the markers, from the files present now.
status_block() {
  local names=() known=() entry name desc dir first stamp commit date machine
  for entry in "${SWEEPS[@]}"; do known+=("${entry%%|*}"); done
  # The README's sweeps first, in their order, then any other folder with a summary, sorted.
  for name in "${known[@]}"; do
    [ -f "$RESULTS/$name/summary.md" ] && names+=("$name")
  done
  for dir in "$RESULTS"/*/; do
    [ -f "$dir/summary.md" ] || continue
    name="$(basename "$dir")"
    case " ${known[*]} " in *" $name "*) ;; *) names+=("$name") ;; esac
  done
  echo "<!-- Written by \`bash docs/results/update.sh\` from docs/results/*/summary.md and STAMP: do not edit by hand. -->"
  if [ "${#names[@]}" -eq 0 ]; then
    echo "**No generated figures on this checkout yet**: \`bash docs/results/update.sh\` runs the sweeps and writes them"
    echo "([docs/how-to/sweeps.md](docs/how-to/sweeps.md)). Until then, the last figures measured by hand (history, not regenerated):"
    echo
    echo "| what was run | verdict | measured on |"
    echo "|---|---|---|"
    for entry in "${HISTORY[@]}"; do
      local file="${entry%%|*}"
      desc="${entry#*|}"
      [ -f "$file" ] || continue
      first="$(heading "$file")"
      commit="$(sed -n 's/.*last written by commit \([0-9a-f]*\) (\([0-9-]*\)).*/\1, \2/p' "$file" | head -n 1)"
      echo "| $desc: [$(basename "$file")]($file) | $first | ${commit:-unknown commit} |"
    done
    return
  fi
  echo "| what was run | verdict (first line of its summary) | measured on |"
  echo "|---|---|---|"
  for name in "${names[@]}"; do
    desc="$name"
    for entry in "${SWEEPS[@]}"; do
      if [ "${entry%%|*}" = "$name" ]; then desc="${entry#*|}"; desc="${desc%%|*}"; fi
    done
    first="$(heading "$RESULTS/$name/summary.md")"
    stamp="$RESULTS/$name/STAMP"
    if [ -f "$stamp" ]; then
      commit="$(stamp_field "$stamp" commit)"
      date="$(stamp_field "$stamp" date)"
      machine="$(stamp_field "$stamp" machine)"
      echo "| $desc: [$name]($RESULTS/$name/summary.md) | ${first:-no heading} | commit ${commit:0:10}${commit:40}, ${date:0:10}, $machine |"
    else
      echo "| $desc: [$name]($RESULTS/$name/summary.md) | ${first:-no heading} | no STAMP: commit unknown |"
    fi
  done
  if [ -f "$RESULTS/compare-known-room.md" ]; then
    echo
    echo "With and without the room known, run by run: [compare-known-room.md]($RESULTS/compare-known-room.md)."
  fi
}

# README.md with the status box replaced (on stdout).
readme_with_status() {
  local block
  block="$(status_block)"
  if [ "$(grep -cxF "$BEGIN" "$README")" != 1 ] || [ "$(grep -cxF "$END" "$README")" != 1 ]; then
    echo "update.sh: $README must hold exactly one '$BEGIN' line and one '$END' line" >&2
    return 2
  fi
  BLOCK="$block" awk -v b="$BEGIN" -v e="$END" '
    $0 == b { print; print ENVIRON["BLOCK"]; skip = 1; next }
    $0 == e { skip = 0 }
    !skip { print }
  ' "$README"
}

write_status() {
  local tmp
  tmp="$(mktemp)"
  readme_with_status >"$tmp"
  cat "$tmp" >"$README"
  rm -f "$tmp"
  echo "update.sh: rewrote the status box of $README"
}

check_status() {
  local tmp
  tmp="$(mktemp)"
  readme_with_status >"$tmp"
  if cmp -s "$tmp" "$README"; then
    rm -f "$tmp"
    echo "update.sh: the status box of $README matches docs/results/"
    return 0
  fi
  echo "update.sh: the status box of $README is not what docs/results/ says; run 'bash docs/results/update.sh --status' (diff: README, expected)" >&2
  diff "$README" "$tmp" >&2 || true
  rm -f "$tmp"
  return 1
}

run_all() {
  local explobot commit date machine entry name args code failed=0
  commit="$(git rev-parse HEAD)"
  if ! git diff --quiet HEAD -- . ":(exclude)$RESULTS" ":(exclude)$README"; then
    commit="$commit (with uncommitted changes)"
  fi
  if [ -n "${EXPLOBOT:-}" ]; then
    explobot="$EXPLOBOT"
    commit="$commit (binary $EXPLOBOT given, not built here)"
  else
    export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$HOME/.cache/explobot-target}"
    cargo build --release --locked -p explobot --bin explobot
    explobot="$CARGO_TARGET_DIR/release/explobot"
  fi
  machine="$(uname -m), $(nproc) cores"
  for entry in "${SWEEPS[@]}"; do
    name="${entry%%|*}"
    args="${entry##*|}"
    if [ -n "${ONLY:-}" ] && [ "$name" != "$ONLY" ]; then
      continue
    fi
    rm -rf "${RESULTS:?}/$name"
    date="$(date -u +%Y-%m-%dT%H:%M:%SZ)"
    echo "update.sh: explobot sweep $args --out $RESULTS/$name"
    code=0
    # shellcheck disable=SC2086 # the arguments are words, and scenarios/*.ron a glob, on purpose
    "$explobot" sweep $args --quiet --out "$RESULTS/$name" || code=$?
    # 0: every run passes, 1: some do not (a verdict, not an error); anything else is an error.
    if [ "$code" -gt 1 ]; then
      echo "update.sh: the sweep $name failed with exit code $code" >&2
      exit "$code"
    fi
    printf 'commit: %s\ndate: %s\nmachine: %s\ncommand: explobot sweep %s --out %s\n' \
      "$commit" "$date" "$machine" "$args" "$RESULTS/$name" >"$RESULTS/$name/STAMP"
  done
  # Needs both folders' results.jsonl, so it runs before they are pruned.
  echo "update.sh: explobot sweep compare $RESULTS/generated-600 $RESULTS/generated-600-known-room"
  if ! "$explobot" sweep compare "$RESULTS/generated-600" "$RESULTS/generated-600-known-room" \
    >"$RESULTS/compare-known-room.md.tmp"; then
    echo "update.sh: 'explobot sweep compare' failed; $RESULTS/compare-known-room.md not written" >&2
    rm -f "$RESULTS/compare-known-room.md.tmp"
    failed=1
  else
    mv "$RESULTS/compare-known-room.md.tmp" "$RESULTS/compare-known-room.md"
  fi
  for entry in "${SWEEPS[@]}"; do
    name="${entry%%|*}"
    case "$name" in
      # The baselines keep their runs, so that a later sweep can be paired with them run by run
      # (`explobot sweep compare`).
      generated-600 | generated-600-known-room)
        find "$RESULTS/$name" -mindepth 1 -not -name summary.md -not -name STAMP -not -name results.jsonl -delete
        ;;
      *) find "$RESULTS/$name" -mindepth 1 -not -name summary.md -not -name STAMP -delete ;;
    esac
  done
  write_status
  return "$failed"
}

case "${1:-}" in
  "") run_all ;;
  --only)
    ONLY="${2:-}"
    known=0
    for entry in "${SWEEPS[@]}"; do [ "${entry%%|*}" = "$ONLY" ] && known=1; done
    if [ "$known" = 0 ]; then
      echo "update.sh: --only needs one of: $(for e in "${SWEEPS[@]}"; do printf '%s ' "${e%%|*}"; done)" >&2
      exit 2
    fi
    run_all
    ;;
  --status) write_status ;;
  --check) check_status ;;
  -h | --help) sed -n '2,20p' "$0" | sed 's/^# \{0,1\}//' ;;
  *)
    echo "usage: bash docs/results/update.sh [--only NAME | --status | --check]" >&2
    exit 2
    ;;
esac
