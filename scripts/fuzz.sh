#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (ASan + UBSan) in build-fuzz/ and runs each for a
# while. Usage: scripts/fuzz.sh [seconds per target, default 60]
# Seed corpora: the shipped .yarns swatches and fuzz/seeds/. Findings go to
# build-fuzz/artifacts/<target>/; keep each as a regression input in tests/data/io/fuzz/.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
build_dir=${KNIT_FUZZ_BUILD_DIR:-build-fuzz}
jobs=${KNIT_JOBS:-1}
targets=(fuzz_yarns fuzz_bcc fuzz_obj fuzz_kstate)

# a machine without clang's libFuzzer runtime cannot fuzz: say so and stop cleanly
probe=$(mktemp -d)
echo 'extern "C" int LLVMFuzzerTestOneInput(const unsigned char*, unsigned long) { return 0; }' >"$probe/p.cpp"
if ! command -v clang++ >/dev/null || ! clang++ -fsanitize=fuzzer "$probe/p.cpp" -o "$probe/p" 2>/dev/null; then
  rm -rf "$probe"
  echo "fuzz: skipped (clang++ with -fsanitize=fuzzer is not available here)"
  exit 0
fi
rm -rf "$probe"

if [ ! -f "$build_dir/build.ninja" ]; then
  CC=clang CXX=clang++ cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DKNIT_BUILD_FUZZ=ON -DKNIT_BUILD_TESTS=OFF -DKNIT_BUILD_BENCH=OFF >/dev/null
fi
if ! cmake --build "$build_dir" -j "$jobs" --target "${targets[@]}" >"$build_dir/build.log" 2>&1; then
  cat "$build_dir/build.log"
  echo "fuzz: build failed" >&2
  exit 1
fi

shared=tests/data/yarns
status=0
for t in "${targets[@]}"; do
  corpus="$build_dir/corpus/$t"
  artifacts="$build_dir/artifacts/$t"
  mkdir -p "$corpus" "$artifacts"
  case $t in
    fuzz_yarns) [ -d "$shared" ] && cp -n "$shared"/*.yarns "$corpus"/ 2>/dev/null || true ;;
    fuzz_bcc) cp -n fuzz/seeds/bcc/* "$corpus"/ ;;
    fuzz_obj) cp -n fuzz/seeds/obj/* "$corpus"/ ;;
    fuzz_kstate) cp -n fuzz/seeds/kstate/* "$corpus"/ ;;
  esac
  echo "fuzz: $t for ${seconds}s"
  if ! "$build_dir/$t" "$corpus" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
      -max_len=131072 -artifact_prefix="$artifacts/" -print_final_stats=1 \
      >"$build_dir/$t.log" 2>&1; then
    echo "fuzz: $t found a problem (see $build_dir/$t.log and $artifacts/)" >&2
    status=1
  fi
  grep -E "^stat::number_of_executed_units|^Done" "$build_dir/$t.log" || true
done
exit $status
