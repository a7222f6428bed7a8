#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (ASan + UBSan) in build-fuzz/ and runs each for a
# while. Usage: scripts/fuzz.sh [seconds per target, default 60]
# Installs what is missing first (the build's packages, clang and its libFuzzer runtime),
# and fails when a target cannot be built or run, finds a problem, or ran no input at all.
# Seed corpora: the shipped .yarns swatches and fuzz/seeds/<kind>/ (knitout: small programs
# and the first lines of bigger ones). Findings go to
# build-fuzz/artifacts/<target>/; keep each as a regression input in tests/data/io/fuzz/.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
build_dir=${KNIT_FUZZ_BUILD_DIR:-build-fuzz}
jobs=${KNIT_JOBS:-1}
targets=(fuzz_yarns fuzz_bcc fuzz_obj fuzz_kstate fuzz_scene fuzz_chart fuzz_knitout fuzz_chart_graph)

scripts/setup.sh --install-only
# libclang-rt-dev is the runtime (libclang_rt.fuzzer) of the default clang (14 on Debian 12)
bash scripts/apt-install.sh --why fuzz clang libclang-rt-dev

# clang must be able to link a fuzzer: without it there is no fuzzing, which is a failure
probe=$(mktemp -d)
trap 'rm -rf "$probe"' EXIT
echo 'extern "C" int LLVMFuzzerTestOneInput(const unsigned char*, unsigned long) { return 0; }' >"$probe/p.cpp"
if ! clang++ -fsanitize=fuzzer "$probe/p.cpp" -o "$probe/p" 2>"$probe/err"; then
  cat "$probe/err" >&2
  echo "fuzz: clang++ -fsanitize=fuzzer cannot link a fuzzer here (libFuzzer runtime missing?)" >&2
  exit 1
fi

if [ ! -f "$build_dir/build.ninja" ]; then
  # -g1: line tables for the sanitizers' stack traces, without full debug info (a faster build)
  CC=clang CXX=clang++ cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" \
    -DKNIT_BUILD_FUZZ=ON -DKNIT_BUILD_TESTS=OFF -DKNIT_BUILD_BENCH=OFF >/dev/null
fi
if ! cmake --build "$build_dir" -j "$jobs" --target "${targets[@]}" >"$build_dir/build.log" 2>&1; then
  cat "$build_dir/build.log"
  echo "fuzz: build failed" >&2
  exit 1
fi

status=0
for t in "${targets[@]}"; do
  corpus="$build_dir/corpus/$t"
  artifacts="$build_dir/artifacts/$t"
  mkdir -p "$corpus" "$artifacts"
  # the largest input each reader is fed: whole yarn files, scenes (a yarn's points are
  # listed in them), and charts (a few lines)
  max_len=131072
  case $t in
    fuzz_yarns) cp -n tests/data/yarns/*.yarns "$corpus"/ ;;
    fuzz_bcc) cp -n fuzz/seeds/bcc/* "$corpus"/ ;;
    fuzz_obj) cp -n fuzz/seeds/obj/* "$corpus"/ ;;
    fuzz_kstate) cp -n fuzz/seeds/kstate/* "$corpus"/ ;;
    fuzz_scene)
      cp -n fuzz/seeds/scene/* "$corpus"/
      max_len=65536
      ;;
    fuzz_chart)
      cp -n fuzz/seeds/chart/* "$corpus"/
      max_len=2048
      ;;
    fuzz_knitout)
      cp -n fuzz/seeds/knitout/* "$corpus"/
      max_len=8192
      ;;
    fuzz_chart_graph)
      cp -n fuzz/seeds/chart_graph/* "$corpus"/
      max_len=4096
      ;;
  esac
  echo "fuzz: $t for ${seconds}s"
  log="$build_dir/$t.log"
  if ! "$build_dir/$t" "$corpus" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
      -max_len="$max_len" -artifact_prefix="$artifacts/" -print_final_stats=1 >"$log" 2>&1; then
    tail -n 40 "$log" >&2
    echo "fuzz: $t found a problem (see $log and $artifacts/)" >&2
    status=1
    continue
  fi
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
  echo "fuzz: $t ran ${runs:-no} inputs"
  if [ -z "$runs" ] || [ "$runs" -eq 0 ]; then
    tail -n 20 "$log" >&2
    echo "fuzz: $t ran no input (see $log)" >&2
    status=1
  fi
done
exit $status
