#!/bin/sh
# Builds the netlist libFuzzer target with clang (ASan + UBSan, coverage on the netlist library)
# in build-netlist-fuzz/ and runs it for a bounded time, seeded with every test netlist.
#   tests/netlist/run-fuzz.sh [seconds]        (default 60)
set -eu
seconds=${1:-60}
root=$(cd "$(dirname "$0")/../.." && pwd)
build="$root/build-netlist-fuzz"
cmake -S "$root" -B "$build" -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DPADSIM_FUZZ=ON -DPADSIM_TESTS=ON \
  -DCMAKE_CXX_FLAGS="-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" >/dev/null
cmake --build "$build" -j2 --target netlist_fuzz
corpus="$build/netlist-corpus"
mkdir -p "$corpus"
find "$root/circuits" "$root/tests/netlist/data" -name '*.cir' -exec cp {} "$corpus/" \; 2>/dev/null || true
# Run where relative includes of fuzz inputs find nothing to read.
mkdir -p "$build/netlist-fuzz-run"
cd "$build/netlist-fuzz-run"
"$build/tests/netlist/netlist_fuzz" -max_total_time="$seconds" -max_len=4096 -timeout=10 \
  -rss_limit_mb=2048 -print_final_stats=1 "$corpus"
