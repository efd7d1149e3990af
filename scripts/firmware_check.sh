#!/usr/bin/env bash
# scripts/firmware_check.sh - proves the gearsim C core is firmware-ready on a
# Cortex-M4F (docs/firmware.md):
#   1. cross build (cmake/toolchain-cortex-m4f.cmake, single precision) at -O2
#      and -Os, plus the host twin of the scenario program (host float build);
#   2. symbols: the library references nothing but memcpy/memset (no heap,
#      stdio, exit/abort, libm, soft-float double helpers), exports only gs_*,
#      has no .data/.bss, no double-precision instruction, and the size-probe
#      programs link none of the forbidden routines;
#   3. code and data size per model (size probes, from the link maps), and the
#      RAM of one instance: its state, apart from its constants;
#   4. worst-case stack per public function (-fstack-usage + -fcallgraph-info);
#   5. the scenario program under QEMU mps2-an386 (wrapped in timeout) against
#      the host program: every output of every step bit for bit, and the
#      instructions per step counted by QEMU (-icount);
#   6. the board's start-up without a C runtime (firmware/board_check.c):
#      .data, .bss, the counter, and the exit status of a return and a fault.
# Exits non-zero when a check fails. Environment: FW_STACK_BUDGET (bytes,
# default 2048), FW_MAX_ULP (allowed QEMU/host difference, default 0),
# FW_QEMU_TIMEOUT (seconds, default 120), FW_BUILD_DIR (default build/firmware).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
t_start=$(date +%s)

stack_budget=${FW_STACK_BUDGET:-2048}
max_ulp=${FW_MAX_ULP:-0}
qemu_timeout=${FW_QEMU_TIMEOUT:-120}
out=${FW_BUILD_DIR:-build/firmware}
jobs=$(nproc 2>/dev/null || echo 2)

# ---- tools: the Debian packages, installed through scripts/setup.sh when missing
need=()
for pkg in cmake make gcc python3 gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm; do
  dpkg -s "$pkg" >/dev/null 2>&1 || need+=("$pkg")
done
if ((${#need[@]})); then
  scripts/setup.sh "${need[@]}"
fi

failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
pass() { echo "ok:   $*"; }
section() { printf '\n== %s\n' "$*"; }

mkdir -p "$out"
tc="$root/cmake/toolchain-cortex-m4f.cmake"
declare -A build_type=([O2]=RelWithDebInfo [Os]=MinSizeRel)

section "1. builds"
for opt in O2 Os; do
  dir="$out/m4f-$opt"
  cmake -S firmware -B "$dir" -DCMAKE_TOOLCHAIN_FILE="$tc" -DCMAKE_BUILD_TYPE="${build_type[$opt]}" \
    "-DCMAKE_C_FLAGS=-fstack-usage -fcallgraph-info=su" >"$out/configure-$opt.log" 2>&1 ||
    { cat "$out/configure-$opt.log"; fail "configure m4f-$opt"; continue; }
  if cmake --build "$dir" -j "$jobs" >"$out/build-$opt.log" 2>&1; then
    pass "Cortex-M4F build -$opt (${build_type[$opt]}, -Werror, single precision): $dir"
  else
    tail -30 "$out/build-$opt.log"; fail "build m4f-$opt"
  fi
done
cmake -S firmware -B "$out/host" -DCMAKE_BUILD_TYPE=RelWithDebInfo >"$out/configure-host.log" 2>&1 &&
  cmake --build "$out/host" -j "$jobs" >"$out/build-host.log" 2>&1 &&
  pass "host twin (float build, -O2): $out/host/gearsim_scenarios" ||
  { tail -30 "$out/build-host.log" 2>/dev/null; fail "host build"; }
if ((failures)); then
  echo "firmware_check: build failed, stopping"; exit 1
fi

section "2. symbols and ABI (libgearsim.a, arm-none-eabi)"
forbidden='^(malloc|free|calloc|realloc|reallocf|memalign|aligned_alloc|_malloc_r|_free_r|_calloc_r|_realloc_r|_sbrk|_sbrk_r|sbrk|brk|printf|fprintf|sprintf|snprintf|vprintf|vfprintf|vsprintf|vsnprintf|iprintf|siprintf|fiprintf|_printf_r|_vfprintf_r|_svfprintf_r|puts|fputs|putchar|fputc|putc|fopen|fclose|fread|fwrite|fflush|_write|_write_r|_read|_open|_close|_lseek|_fstat|_isatty|exit|_exit|abort|atexit|__assert_func|__assert|raise|signal|_kill|_getpid|__errno|errno|tanh|tanhf|exp|expf|log|logf|pow|powf|sqrt|sqrtf|sin|sinf|cos|cosf|tan|tanf|atan|atanf|atan2|atan2f|fmod|fmodf|floor|floorf|ceil|ceilf|__aeabi_d[a-z0-9]*|__aeabi_[fli]2d|__aeabi_ul2d|__(add|sub|mul|div|neg)df3|__(eq|ne|lt|le|gt|ge|un|cmp)df2|__extendsfdf2|__truncdfsf2|__fix(uns)?df[sd]i|__float(un)?[sd]idf)$'
for opt in O2 Os; do
  lib="$out/m4f-$opt/gearsim/libgearsim.a"
  defined=$(arm-none-eabi-nm -g --defined-only "$lib" | awk 'NF==3{print $3}' | sort -u)
  undefined=$(arm-none-eabi-nm -u "$lib" | awk 'NF==2{print $2}' | sort -u)
  external=$(comm -23 <(echo "$undefined") <(echo "$defined") | tr '\n' ' ')
  unexpected=$(comm -23 <(echo "$undefined") <(echo "$defined") | grep -v -x -E 'memcpy|memset' || true)
  if [ -z "$unexpected" ]; then
    pass "-$opt: external references: ${external:-none} (allowed: memcpy memset)"
  else
    fail "-$opt: unexpected external references: $(echo "$unexpected" | tr '\n' ' ')"
  fi
  bad=$(comm -23 <(echo "$undefined") <(echo "$defined") | grep -E "$forbidden" || true)
  [ -z "$bad" ] && pass "-$opt: no heap, stdio, exit/abort, libm or __aeabi_d*/__*df* reference" ||
    fail "-$opt: forbidden references: $(echo "$bad" | tr '\n' ' ')"
  noprefix=$(echo "$defined" | grep -v -E '^gs_' || true)
  [ -z "$noprefix" ] && pass "-$opt: $(echo "$defined" | wc -l) exported symbols, all gs_*" ||
    fail "-$opt: exported symbols without the gs_ prefix: $(echo "$noprefix" | tr '\n' ' ')"
  read -r _ data bss _ < <(arm-none-eabi-size -t "$lib" | tail -1)
  [ "$data" = 0 ] && [ "$bss" = 0 ] && pass "-$opt: .data 0 B, .bss 0 B (no mutable statics)" ||
    fail "-$opt: library has .data $data B / .bss $bss B"
  f64=$(arm-none-eabi-objdump -d "$lib" | grep -c -E '\.f64|vcvt\.f64|\bvmov\b.*\bd[0-9]+\b' || true)
  [ "$f64" = 0 ] && pass "-$opt: no double-precision instruction in the disassembly" ||
    fail "-$opt: $f64 double-precision instructions"
  attrs=$(arm-none-eabi-readelf -A "$lib")
  if grep -q 'Tag_CPU_arch: v7E-M' <<<"$attrs" && grep -q 'Tag_THUMB_ISA_use: Thumb-2' <<<"$attrs" &&
     grep -q 'Tag_ABI_VFP_args: VFP registers' <<<"$attrs" && grep -q 'Tag_ABI_HardFP_use: SP only' <<<"$attrs" &&
     ! grep -q 'Tag_CPU_arch: v4' <<<"$attrs"; then
    enum_size=$(grep -m1 'Tag_ABI_enum_size' <<<"$attrs" | sed 's/.*: //')
    pass "-$opt: objects are ARMv7E-M Thumb-2, hard-float (VFP argument registers, SP only); enum size: $enum_size"
  else
    fail "-$opt: build attributes are not Cortex-M4F hard-float"
  fi
  for elf in "$out/m4f-$opt"/probe_*.elf; do
    pulled=$(arm-none-eabi-nm "$elf" | awk 'NF==3{print $3}' | grep -E "$forbidden" || true)
    [ -z "$pulled" ] || fail "-$opt: $(basename "$elf") links $(echo "$pulled" | tr '\n' ' ')"
  done
  [ -z "${pulled:-}" ] && pass "-$opt: size probes link no forbidden routine ($(ls "$out/m4f-$opt"/probe_*.elf | wc -l) programs)"
done

section "3. code and data size per model (bytes, Cortex-M4F, from the link maps)"
for opt in O2 Os; do
  echo "-$opt  model           gearsim .text  .rodata  .data  .bss  | probe .bss | RAM per instance: state | constants | +newlib memcpy/memset"
  python3 firmware/tools/map_sizes.py "$out/m4f-$opt"/probe_*.map | sort >"$out/sizes-$opt.txt"
  base_bss=$(awk '$1=="probe_baseline"{print $9}' "$out/sizes-$opt.txt")
  while read -r name text rodata data bss libc _otext _odata obss; do
    [ "$name" = probe_baseline ] && continue
    # the probe's fw_state_* (what a step updates) and fw_consts_* (what init
    # derives, read-only afterwards: in .bss here, or flash as an image)
    read -r state consts < <(arm-none-eabi-nm -S --radix=d "$out/m4f-$opt/$name.elf" |
      awk 'NF==4 && $4 ~ /^fw_state_/ {s += $2} NF==4 && $4 ~ /^fw_consts_/ {c += $2}
           END {print s + 0, c + 0}')
    printf '     %-15s %13d %8d %6d %5d  | %10d | %23d | %9d | %d\n' "${name#probe_}" \
      "$text" "$rodata" "$data" "$bss" $((obss - base_bss)) "$state" "$consts" "$libc"
    [ "$data" = 0 ] && [ "$bss" = 0 ] || fail "-$opt: ${name#probe_} takes .data/.bss in the library"
  done <"$out/sizes-$opt.txt"
  echo "     per source file (arm-none-eabi-size, text = code + constants):"
  arm-none-eabi-size "$out/m4f-$opt/gearsim/libgearsim.a" |
    awk 'NR>1{sub(/ \(ex .*/, "", $6); printf "       %-18s %6d text %3d data %3d bss\n", $6, $1, $2, $3; t+=$1} END{printf "       %-18s %6d text\n", "total", t}'
done

section "4. worst-case stack per public function (bytes, Cortex-M4F)"
for opt in O2 Os; do
  echo "-$opt (budget $stack_budget B):"
  if python3 firmware/tools/stack_report.py --objdir "$out/m4f-$opt/gearsim" --headers include/gearsim \
      --elf "$out/m4f-$opt/probe_both_rigs.elf" --objdump arm-none-eabi-objdump --budget "$stack_budget" \
      | sed 's/^/  /' | tee "$out/stack-$opt.txt" | grep -q FAIL; then
    cat "$out/stack-$opt.txt"; fail "-$opt: stack analysis"
  else
    cat "$out/stack-$opt.txt"
  fi
done

section "5. QEMU mps2-an386 vs host, bit for bit"
"$out/host/gearsim_scenarios" >"$out/host.txt" || fail "host scenario program exited $?"
for opt in O2 Os; do
  elf="$out/m4f-$opt/gearsim_scenarios.elf"
  t0=$(date +%s.%N)
  rc=0
  timeout "$qemu_timeout" qemu-system-arm -M mps2-an386 -nographic -semihosting -icount shift=0 \
    -kernel "$elf" >"$out/qemu-$opt.txt" 2>"$out/qemu-$opt.err" || rc=$?
  t1=$(date +%s.%N)
  secs=$(python3 -c "print(f'{$t1-$t0:.1f}')")
  if [ "$rc" = 124 ]; then
    fail "-$opt: QEMU timed out after ${qemu_timeout}s (the program never ended)"; continue
  elif [ "$rc" != 0 ]; then
    fail "-$opt: QEMU program exited $rc"; tail -n 5 "$out/qemu-$opt.txt" "$out/qemu-$opt.err"; continue
  fi
  pass "-$opt: QEMU run ended normally in ${secs}s: $(grep '^done' "$out/qemu-$opt.txt")"
  grep '^# layout' "$out/qemu-$opt.txt" | sed 's/^# /  target /'
  [ "$opt" = O2 ] && grep '^# layout' "$out/host.txt" | sed 's/^# /  host   /'
  cal=$(sed -n 's/^# calibration \([0-9]*\) .*/\1/p' "$out/qemu-$opt.txt")
  if [ -n "$cal" ] && [ "$cal" -ge 198000 ] && [ "$cal" -le 202000 ]; then
    pass "-$opt: instruction counter calibrated: $cal counted for 200000 executed"
  else
    fail "-$opt: instruction counter calibration off: ${cal:-none} for 200000"
  fi
  echo "  instructions per gs_rig_step (QEMU -icount; instructions, not cycles):"
  sed -n 's/^# cost \([^ ]*\) \([0-9]*\) .*, \([0-9]*\) contact sub-steps.*/\1 \2 \3/p' "$out/qemu-$opt.txt" |
    awk '{printf "    %-24s %6d%s\n", $1, $2, ($3 > 0) ? sprintf("   (backlash, %d contact sub-steps: %d per sub-step)", $3, $2 / $3) : ""}'
  if python3 firmware/tools/compare_outputs.py "$out/host.txt" "$out/qemu-$opt.txt" --max-ulp "$max_ulp" \
      >"$out/compare-$opt.txt"; then
    sed 's/^/  /' "$out/compare-$opt.txt"
    pass "-$opt: QEMU outputs match the host within $max_ulp ULP ($(tail -1 "$out/compare-$opt.txt" | cut -d: -f2 | cut -d, -f1 | sed 's/^ //'))"
  else
    sed 's/^/  /' "$out/compare-$opt.txt"; fail "-$opt: QEMU outputs differ from the host"
  fi
done

section "6. the board's start-up without a C runtime (firmware/mps2-an386)"
for opt in O2 Os; do
  for check in return:0 fail:1 fault:1; do
    name=board_check_${check%%:*} want=${check##*:} rc=0
    timeout 20 qemu-system-arm -M mps2-an386 -nographic -semihosting -icount shift=0 \
      -kernel "$out/m4f-$opt/$name.elf" >"$out/$name-$opt.txt" 2>&1 || rc=$?
    said=$(tr '\n' ' ' <"$out/$name-$opt.txt" | sed 's/ *$//')
    if [ "$rc" = "$want" ] && { [ "$name" != board_check_return ] || [ "$said" = "board: ok" ]; }; then
      pass "-$opt: $name: QEMU exit status $rc${said:+ ($said)}"
    else
      fail "-$opt: $name: QEMU exit status $rc (want $want; 124: timed out)${said:+: $said}"
    fi
  done
done

section "summary"
echo "firmware_check: $failures failure(s), $(( $(date +%s) - t_start ))s"
exit $((failures > 0))
