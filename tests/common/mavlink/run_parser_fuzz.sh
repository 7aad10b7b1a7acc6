#!/bin/sh
# Builds the MAVLink parser fuzzer with clang++ (libFuzzer + ASan + UBSan) and runs it briefly with a fixed
# seed. Exit 77 (ctest SKIP_RETURN_CODE) when clang++ or its libFuzzer runtime is missing.
# usage: run_parser_fuzz.sh <repo root> <work dir>   env: FUZZ_RUNS (default 200000), FUZZ_MAX_S (default 20)
set -eu
root=$1
work=$2
CXX_FUZZ=${CXX_FUZZ:-clang++}
if ! command -v "$CXX_FUZZ" >/dev/null 2>&1; then
  echo "SKIP: $CXX_FUZZ not found"
  exit 77
fi
mkdir -p "$work"
bin="$work/mavlink_parser_fuzz"
src="$root/common/src/mavlink"
inc="$root/common/include"
sources="$root/tests/common/mavlink/parser_fuzz.cpp $src/codec.cpp $src/parser.cpp
  $src/sha256.cpp $src/signing.cpp $src/generated/message_table.cpp $src/generated/messages.cpp"

# rebuild only when a source or header is newer than the binary (keeps repeated ctest runs short)
stale=1
if [ -x "$bin" ] && [ -z "$(find "$src" "$inc" "$root/tests/common/mavlink/parser_fuzz.cpp" -newer "$bin" \
      \( -name '*.cpp' -o -name '*.hpp' \) 2>/dev/null | head -n 1)" ]; then
  stale=0
fi
if [ "$stale" = 1 ]; then
  # probe first: clang without its libFuzzer runtime is a skip, not a failure
  probe="$work/probe.cpp"
  printf '%s\n' '#include <cstdint>' '#include <cstddef>' \
    'extern "C" int LLVMFuzzerTestOneInput(const uint8_t*, size_t) { return 0; }' > "$probe"
  if ! "$CXX_FUZZ" -std=c++20 -fsanitize=fuzzer "$probe" -o "$work/probe" >/dev/null 2>&1; then
    echo "SKIP: $CXX_FUZZ cannot link -fsanitize=fuzzer"
    exit 77
  fi
  echo "building $bin"
  # shellcheck disable=SC2086
  "$CXX_FUZZ" -std=c++20 -O1 -g -fno-omit-frame-pointer -fsanitize=fuzzer,address,undefined \
    -fno-sanitize-recover=undefined -I"$inc" $sources -o "$bin.tmp"
  mv "$bin.tmp" "$bin"
fi

# seed corpus: the reference frames, one file each
# (fresh each run, so every run starts from the same corpus and -seed=1 makes it repeatable)
corpus="$work/corpus"
rm -rf "$corpus"
mkdir -p "$corpus"
if command -v xxd >/dev/null 2>&1; then
  grep -v '^#' "$root/tests/data/mavlink/test_vectors.txt" | while read -r label hex; do
    [ -n "$hex" ] || continue
    # leading mode byte 0x00: no signing key, byte-wise chunks
    printf '00%s' "$hex" | xxd -r -p > "$corpus/$label"
  done
fi

cd "$work"
"$bin" -seed=1 -runs="${FUZZ_RUNS:-200000}" -max_total_time="${FUZZ_MAX_S:-20}" -max_len=2048 \
  -print_final_stats=1 "$corpus"
