#!/usr/bin/env bash
# Run every fuzz target for SECONDS each (default 60), seeded with the real
# files in ../shared (capture, recordings) and the project's own libraries
# and configurations. Exits non-zero when any target crashes; the input
# that crashed it is in fuzz/artifacts/TARGET/.
#
# Needs the nightly toolchain and cargo-fuzz:
#   rustup toolchain install nightly && cargo install cargo-fuzz
set -u
seconds=${1:-60}
here=$(cd "$(dirname "$0")" && pwd)
root=$(dirname "$here")
shared=${MARIONETTE_SHARED:-$root/../shared}
cd "$here"

if ! cargo +nightly fuzz --help >/dev/null 2>&1; then
    echo "fuzz/run.sh: needs nightly and cargo-fuzz:" >&2
    echo "  rustup toolchain install nightly && cargo install cargo-fuzz" >&2
    exit 2
fi

seed() { # seed TARGET FILE... : copy the files into TARGET's corpus
    local target=$1
    shift
    mkdir -p "corpus/$target"
    for f in "$@"; do
        [ -f "$f" ] && cp -L "$f" "corpus/$target/seed-$(basename "$f")"
    done
}

seed bvh_parse $(find "$shared/mocap" -name '*.bvh' -size -200k | sort | head -40) "$root"/assets/library/*.bvh
seed evemu_parse "$shared"/recordings/evemu/*.evemu "$root"/assets/recordings/*.evemu
seed library_toml "$root"/assets/library/library.toml "$root"/tests/libraries/*/library.toml
seed config "$root"/config/*.toml
seed gltf "$shared"/characters/RiggedFigure.glb
# The door: a kind byte (0 a file, 1 and 2 links in and out, 3 a pipe, 4
# a folder, 5 /dev/zero, 6 a dangling link), a 16-bit limit, the bytes.
mkdir -p corpus/door
k=0
for f in "$shared"/characters/RiggedFigure.glb "$root"/config/*.toml "$root"/assets/library/library.toml \
    $(ls "$shared"/recordings/evemu/*.evemu | head -3) $(find "$shared/mocap" -name '*.bvh' -size -20k | sort | head -3); do
    [ -f "$f" ] || continue
    { printf "\\x$(printf %02x $((k % 7)))\\xff\\xff"; head -c 60000 "$f"; } >"corpus/door/seed-$k"
    k=$((k + 1))
done
mkdir -p corpus/init_names corpus/tracker
for name in $(find "$shared/mocap" -name '*.bvh' | head -20); do
    printf '%s' "$(basename "$name" .bvh)" >"corpus/init_names/seed-$(basename "$name")"
done
printf 'take "one"\n# [x]' >corpus/init_names/seed-quotes

status=0
for target in bvh_parse evemu_parse tracker library_toml config init_names gltf door; do
    echo "== $target: $seconds s"
    if ! cargo +nightly fuzz run "$target" "corpus/$target" -- \
        -max_total_time="$seconds" -max_len=65536 -rss_limit_mb=4096 -print_final_stats=1 \
        2>"corpus/$target.log"; then
        echo "== $target: CRASH (fuzz/artifacts/$target/, log fuzz/corpus/$target.log)"
        tail -40 "corpus/$target.log"
        status=1
    else
        grep -E 'stat::number_of_executed_units|Done' "corpus/$target.log" | tail -2
    fi
done
exit $status
