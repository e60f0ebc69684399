#!/usr/bin/env bash
# gpu-bench.sh: build refrakt and time the sweep's two paths (compute and fragment) on this
# machine's GPU, in both light transports, within a time budget; write a dated report.
#
# Usage: bash scripts/gpu-bench.sh [--help]        (from any directory; as root or with sudo)
#
# Meant for a machine with an NVIDIA GPU and its driver (bare Debian bookworm is enough:
# the script installs what is missing). Steps:
#   1. bash scripts/setup.sh (system packages, Rust), source scripts/env.sh; Debian's
#      cargo-web and rustc-web if rustup could not be reached; python3 if missing;
#      cargo build --release --locked.
#   2. ./target/release/refrakt info: the Vulkan device. Exits 1 when the only device is a
#      CPU one (lavapipe), unless REFRAKT_BENCH_ALLOW_CPU=1.
#   3. The thesis rows (supernova piggy-bank glass hand head water ship kiwi), one at a time
#      in that order, each as two `refrakt bench variants` invocations:
#        --light-transport forward  --variant sweep=compute --variant sweep=fragment
#                                   --variant sweep=fragment,splat=compute
#                                   --variant sweep=compute,rays=all
#        --light-transport backward --variant sweep=compute --variant sweep=fragment
#                                   --variant sweep=compute,tile=on
#      (tile=on: the backward plane's light reads from a workgroup tile, issue 31;
#      the same image, off by default until this has timed it on a GPU. rays=all: every
#      light ray moved and deposited on every plane, the compute path's way until
#      2026-12-08; the default, rays=needed, only the grid rows needed by then)
#      each with --scale, --frames, --warmup, --json and wrapped in `timeout` with what is
#      left of the time budget. Rows stop when the budget is spent; the report says which
#      rows ran and why the others did not (time budget, timeout, failure). The budget
#      counts every bench invocation, including the first-use generation of each row's
#      stand-in volume (cached in ~/.cache/refrakt/standins, so a second run is faster);
#      it does not count the build. Then, if budget remains, one
#      `refrakt bench thesis --baselines` on the rows that ran (default transport: forward;
#      baselines = EA ray marcher, sweep floor, skeleton).
#      Then, if budget remains, `refrakt render --pass-timings --variant sweep=compute` of
#      the default scene at 768² times the scale: each pass, and each step of the splat.
#   4. Writes the report and prints the summary table (per row and transport, the median
#      frame ms of sweep=compute and sweep=fragment and their ratio) on stdout. Progress
#      goes to stderr.
#
# Environment (all optional):
#   REFRAKT_BENCH_SCALE=1        --scale (viewport and volume together; 1 = the thesis' size)
#   REFRAKT_BENCH_FRAMES=3       --frames: measured frames per row and variant
#   REFRAKT_BENCH_WARMUP=1       --warmup: warm-up frames per row and variant
#   REFRAKT_BENCH_BUDGET_S=480   time budget in seconds for all bench invocations together
#   REFRAKT_BENCH_ROWS=...       rows to try, comma-separated, in order (default: all eight)
#   REFRAKT_BENCH_DEVICE=...     Vulkan device (index or part of its name, as --device);
#                                default: refrakt's choice (discrete > integrated > ... > CPU)
#   REFRAKT_BENCH_ALLOW_CPU=1    go on when the selected device is a CPU (lavapipe); for tests
#   REFRAKT_BENCH_OUT=docs/bench output folder (relative paths: to the repository root)
#   REFRAKT_BENCH_SKIP_BUILD=1   skip setup.sh and cargo build; use the existing
#                                target/release/refrakt
#
# Outputs (DATE = UTC date, DEVICE = the device name as a slug; -2, -3, ... appended
# rather than overwrite an earlier run's files):
#   $REFRAKT_BENCH_OUT/DATE-DEVICE.json  date, git commit, device, driver (refrakt info and
#                                        nvidia-smi), settings, rows run / not run with
#                                        reasons, every command line, the summary, and each
#                                        invocation's JSON report embedded
#   $REFRAKT_BENCH_OUT/DATE-DEVICE.md    the same for people: device, driver, commit,
#                                        command lines, rows, summary table, baselines
#   target/gpu-bench/DATE-DEVICE/        the raw per-invocation JSON reports and logs
# Exit status: 0 when at least one row ran, 1 otherwise (or on a setup, build or device error).
set -euo pipefail

log() { printf 'gpu-bench: %s\n' "$*" >&2; }
die() { printf 'gpu-bench: error: %s\n' "$*" >&2; exit 1; }

script="${BASH_SOURCE[0]}"
case "${1:-}" in
  -h|--help)
    # The comment block at the top of this file, without its leading '# '.
    sed -n '2,/^set -euo pipefail$/{/^set /d;s/^# \{0,1\}//;p}' "$script"
    exit 0 ;;
  "") ;;
  *) die "unknown argument '$1' (the script takes none but --help; settings are environment variables)" ;;
esac

cd "$(dirname "$script")/.."
root="$(pwd -P)"
[ -f Cargo.toml ] && [ -f scripts/setup.sh ] || die "$root does not look like the refrakt repository"

scale="${REFRAKT_BENCH_SCALE:-1}"
frames="${REFRAKT_BENCH_FRAMES:-3}"
warmup="${REFRAKT_BENCH_WARMUP:-1}"
budget="${REFRAKT_BENCH_BUDGET_S:-480}"
rows_csv="${REFRAKT_BENCH_ROWS:-supernova,piggy-bank,glass,hand,head,water,ship,kiwi}"
device_arg="${REFRAKT_BENCH_DEVICE:-}"
allow_cpu="${REFRAKT_BENCH_ALLOW_CPU:-0}"
out_dir="${REFRAKT_BENCH_OUT:-docs/bench}"
skip_build="${REFRAKT_BENCH_SKIP_BUILD:-0}"

[[ "$scale" =~ ^([0-9]+\.?[0-9]*|\.[0-9]+)$ ]] || die "REFRAKT_BENCH_SCALE='$scale' is not a positive number"
[[ "$frames" =~ ^[1-9][0-9]*$ ]] || die "REFRAKT_BENCH_FRAMES='$frames' is not a positive integer"
[[ "$warmup" =~ ^[0-9]+$ ]] || die "REFRAKT_BENCH_WARMUP='$warmup' is not an integer"
[[ "$budget" =~ ^[1-9][0-9]*$ ]] || die "REFRAKT_BENCH_BUDGET_S='$budget' is not a positive integer (seconds)"
IFS=, read -r -a rows <<<"$rows_csv"
((${#rows[@]})) || die "REFRAKT_BENCH_ROWS is empty"

# An invocation is not started with less than this many seconds of budget left: it could
# not even finish its set-up.
min_start_s=10

# --- 1. Set-up and build ----------------------------------------------------------------

if [ "$(id -u)" -eq 0 ]; then sudo=(); else sudo=(sudo); fi
ensure_python() {
  command -v python3 >/dev/null 2>&1 && return 0
  log "installing python3 (assembles the report)"
  export DEBIAN_FRONTEND=noninteractive
  "${sudo[@]}" apt-get update -qq
  "${sudo[@]}" apt-get install -y -qq --no-install-recommends python3 >/dev/null
  command -v python3 >/dev/null 2>&1 || die "python3 could not be installed"
}

if [ "$skip_build" = 1 ]; then
  log "REFRAKT_BENCH_SKIP_BUILD=1: skipping scripts/setup.sh and cargo build"
  # shellcheck source=scripts/env.sh
  source scripts/env.sh
else
  log "step 1/4: bash scripts/setup.sh (installs missing system packages and Rust)"
  setup_rc=0
  bash scripts/setup.sh || setup_rc=$?
  # shellcheck source=scripts/env.sh
  source scripts/env.sh
  if ! command -v cargo >/dev/null 2>&1; then
    # rustup's installer comes from outside the package registries; where only those are
    # reachable, Debian bookworm's cargo-web/rustc-web (Rust >= 1.80) stand in for it.
    log "no cargo after scripts/setup.sh (exit status $setup_rc): installing Debian's cargo-web and rustc-web"
    export DEBIAN_FRONTEND=noninteractive
    "${sudo[@]}" apt-get update -qq
    "${sudo[@]}" apt-get install -y -qq --no-install-recommends cargo-web rustc-web >/dev/null \
      || die "could not install cargo-web and rustc-web"
    command -v cargo >/dev/null 2>&1 || die "no cargo: install Rust >= 1.80 (rustup or Debian's cargo-web)"
    setup_rc=0
  fi
  if ((setup_rc)); then
    log "WARNING: scripts/setup.sh exited with status $setup_rc; trying the build anyway"
  fi
  log "step 1/4: $(cargo --version), $(rustc --version 2>/dev/null || echo 'rustc ?')"
  log "step 1/4: cargo build --release --locked"
  build_t0=$(date +%s)
  cargo build --release --locked || die "cargo build --release --locked failed"
  log "step 1/4: built in $(($(date +%s) - build_t0)) s"
fi
ensure_python
bin="$root/target/release/refrakt"
[ -x "$bin" ] || die "$bin not found (build it, or unset REFRAKT_BENCH_SKIP_BUILD)"

# --- 2. The device ----------------------------------------------------------------------

log "step 2/4: refrakt info${device_arg:+ --device $device_arg}"
info_cmd=("$bin" info)
if [ -n "$device_arg" ]; then info_cmd+=(--device "$device_arg"); fi
if ! info_out="$("${info_cmd[@]}" 2>&1)"; then
  printf '%s\n' "$info_out" >&2
  die "refrakt info failed: no usable Vulkan device (is libvulkan1 installed, and the NVIDIA
Vulkan ICD, /usr/share/vulkan/icd.d/nvidia_icd.json or /etc/vulkan/icd.d/nvidia_icd.json?)"
fi
printf '%s\n' "$info_out" | sed 's/^/  | /' >&2

sel_line="$(printf '%s\n' "$info_out" | sed -n 's/^Selected: //p' | head -n1)"
[ -n "$sel_line" ] || die "could not find the 'Selected:' line in the output of refrakt info"
dev_index="$(printf '%s\n' "$sel_line" | sed -n 's/^\[\([0-9]*\)\] .*/\1/p')"
dev_name="$(printf '%s\n' "$sel_line" | sed -n 's/^\[[0-9]*\] //p')"
dev_type="$(printf '%s\n' "$info_out" | sed -n 's/^  type: *//p' | head -n1)"
dev_vulkan="$(printf '%s\n' "$info_out" | sed -n 's/^  Vulkan version: *//p' | head -n1)"
dev_driver="$(printf '%s\n' "$info_out" | sed -n 's/^  driver: *//p' | head -n1)"
[ -n "$dev_index" ] && [ -n "$dev_name" ] || die "could not parse the selected device from: $sel_line"

nvsmi=""
if command -v nvidia-smi >/dev/null 2>&1; then
  nvsmi="$(nvidia-smi --query-gpu=name,driver_version --format=csv,noheader 2>/dev/null || true)"
  if [ -n "$nvsmi" ]; then log "nvidia-smi: $nvsmi"; fi
fi

case "$dev_type" in
  "discrete GPU"|"integrated GPU"|"virtual GPU")
    log "device: [$dev_index] $dev_name ($dev_type, driver $dev_driver)" ;;
  *)
    gpus="$(printf '%s\n' "$info_out" | grep -E '^ [ *]\[[0-9]+\] .*\((discrete|integrated|virtual) GPU\)' || true)"
    if [ -n "$gpus" ]; then
      log "WARNING: the selected device [$dev_index] $dev_name is a $dev_type, not a GPU;"
      log "         GPU devices listed: $(printf '%s' "$gpus" | tr '\n' ';')"
    else
      log "WARNING: no GPU Vulkan device found; the only device is [$dev_index] $dev_name ($dev_type)."
      log "         Is the NVIDIA driver's Vulkan ICD installed (nvidia_icd.json under"
      log "         /usr/share/vulkan/icd.d or /etc/vulkan/icd.d; Debian: nvidia-vulkan-icd)?"
      if [ -n "$nvsmi" ]; then log "         (nvidia-smi sees: $nvsmi)"; fi
    fi
    if [ "$allow_cpu" = 1 ]; then
      log "WARNING: REFRAKT_BENCH_ALLOW_CPU=1: benchmarking the $dev_type anyway (lavapipe is"
      log "         orders of magnitude slower than a GPU: use a small REFRAKT_BENCH_SCALE)"
    else
      die "no GPU Vulkan device to benchmark (set REFRAKT_BENCH_ALLOW_CPU=1 to run on the $dev_type anyway)"
    fi ;;
esac

# --- Names and folders ------------------------------------------------------------------

date_utc="$(date -u +%Y-%m-%d)"
slug="$(printf '%s' "$dev_name" | tr '[:upper:]' '[:lower:]' | sed -E 's/[^a-z0-9]+/-/g; s/^-+//; s/-+$//' | cut -c1-60 | sed -E 's/-+$//')"
[ -n "$slug" ] || slug=device
case "$out_dir" in /*) ;; *) out_dir="$root/$out_dir" ;; esac
mkdir -p "$out_dir"
base="$date_utc-$slug"
n=1
while [ -e "$out_dir/$base.json" ] || [ -e "$out_dir/$base.md" ]; do
  n=$((n + 1)); base="$date_utc-$slug-$n"
done
work="$root/target/gpu-bench/$base"
rm -rf "$work"
mkdir -p "$work"

standin_dir="${REFRAKT_CACHE_DIR:-${XDG_CACHE_HOME:+$XDG_CACHE_HOME/refrakt}}"
standin_dir="${standin_dir:-$HOME/.cache/refrakt}/standins"

printf '%s\n' "$info_out" >"$work/refrakt-info.txt"
printf '%s\n' "$nvsmi" >"$work/nvidia-smi.txt"
started_utc="$(date -u +%Y-%m-%dT%H:%M:%SZ)"

# One line per invocation: kind row(s) transport status exit_code elapsed_s json log
# standins_generated command (tab-separated; the command shell-quoted).
runs="$work/runs.tsv"
: >"$runs"

# --- 3. The benchmark -------------------------------------------------------------------

common=(--device "$dev_index" --scale "$scale" --frames "$frames" --warmup "$warmup" --quiet)
variants_forward=(--variant sweep=compute --variant sweep=fragment --variant sweep=fragment,splat=compute
                  --variant sweep=compute,rays=all)
variants_backward=(--variant sweep=compute --variant sweep=fragment --variant sweep=compute,tile=on)

t_start=$(date +%s)
remaining() { echo $((budget - ($(date +%s) - t_start))); }
budget_spent=0

# shq ARGS...: the arguments as one shell-quoted line (single quotes only where needed).
shq() {
  local a out=""
  for a in "$@"; do
    if [[ "$a" =~ ^[A-Za-z0-9_./=,:+@%-]+$ ]]; then out+=" $a"
    else out+=" '${a//\'/\'\\\'\'}'"; fi
  done
  printf '%s' "${out# }"
}

# run KIND ROWS TRANSPORT JSON CMD...: runs CMD under `timeout` with the remaining budget,
# appends a line to $runs and sets $last_status.
run() {
  local kind="$1" rows_arg="$2" transport="$3" json="$4"; shift 4
  local logf="${json%.*}.log" left rc=0 t0 t1 status before after new cmd_str
  cmd_str="$(shq "$@")"
  cmd_str="${cmd_str//$root\/target\/release\/refrakt/./target/release/refrakt}"
  cmd_str="${cmd_str//$root\//}"
  left="$(remaining)"
  if ((left < min_start_s)); then
    last_status=budget
    budget_spent=1
    printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$kind" "$rows_arg" "$transport" budget "" 0 "" "" "" "$cmd_str" >>"$runs"
    log "  $kind $rows_arg $transport: not started, ${left} s of the budget left"
    return 0
  fi
  before="$(ls "$standin_dir" 2>/dev/null | sort || true)"
  log "  $kind $rows_arg $transport: running (timeout ${left} s) ..."
  t0=$(date +%s)
  timeout --kill-after=15 "$left" "$@" >"$logf" 2>&1 || rc=$?
  t1=$(date +%s)
  after="$(ls "$standin_dir" 2>/dev/null | sort || true)"
  # New files in the stand-in cache named after this invocation's rows (the cache is shared:
  # other processes may add files too).
  new="$(comm -13 <(printf '%s\n' "$before") <(printf '%s\n' "$after") \
         | grep -E "^(${rows_arg//,/|})_" | tr '\n' ' ' || true)"
  new="${new% }"
  if ((rc == 0)) && [ -s "$json" ]; then
    status=ok
  elif ((rc == 124 || rc == 137)); then
    status=timeout
    budget_spent=1
  else
    status=failed
  fi
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$kind" "$rows_arg" "$transport" "$status" "$rc" \
    $((t1 - t0)) "$json" "$logf" "$new" "$cmd_str" >>"$runs"
  local extra=""
  if [ -n "$new" ]; then extra=" (generated stand-in: $new)"; fi
  case "$status" in
    ok) log "  $kind $rows_arg $transport: done in $((t1 - t0)) s$extra; $(remaining) s of the budget left" ;;
    timeout) log "  $kind $rows_arg $transport: TIMEOUT after $((t1 - t0)) s (the budget ran out)$extra" ;;
    failed)
      log "  $kind $rows_arg $transport: FAILED (exit status $rc) after $((t1 - t0)) s; last lines of $logf:"
      tail -n 15 "$logf" | sed 's/^/  | /' >&2 ;;
  esac
  last_status="$status"
}

log "step 3/4: bench variants, rows ${rows[*]}; scale $scale, $frames frame(s) after $warmup warm-up;"
log "          budget ${budget} s (stand-in generation included); raw reports in ${work#"$root"/}/"
rows_ok=()
i=0
for row in "${rows[@]}"; do
  i=$((i + 1))
  if ((budget_spent)); then
    printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' variants "$row" "" budget "" 0 "" "" "" "" >>"$runs"
    continue
  fi
  log "row $i/${#rows[@]}: $row"
  all_ok=1
  for transport in forward backward; do
    if ((budget_spent)); then
      printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' variants "$row" "$transport" budget "" 0 "" "" "" "" >>"$runs"
      all_ok=0
      continue
    fi
    if [ "$transport" = forward ]; then vs=("${variants_forward[@]}"); else vs=("${variants_backward[@]}"); fi
    json="$work/variants-$transport-$row.json"
    run variants "$row" "$transport" "$json" \
      "$bin" bench variants "${common[@]}" --rows "$row" --light-transport "$transport" "${vs[@]}" --json "$json"
    [ "$last_status" = ok ] || all_ok=0
  done
  if ((all_ok)); then rows_ok+=("$row"); fi
done

if ((${#rows_ok[@]} == 0)); then
  log "baselines: skipped (no row ran)"
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' thesis-baselines "" forward "no-rows" "" 0 "" "" "" "" >>"$runs"
elif ((budget_spent)); then
  log "baselines: skipped (time budget spent)"
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' thesis-baselines "$(IFS=,; echo "${rows_ok[*]}")" forward budget "" 0 "" "" "" "" >>"$runs"
else
  rows_ok_csv="$(IFS=,; echo "${rows_ok[*]}")"
  log "baselines: bench thesis --baselines on $rows_ok_csv"
  json="$work/thesis-baselines.json"
  run thesis-baselines "$rows_ok_csv" forward "$json" \
    "$bin" bench thesis --baselines "${common[@]}" --rows "$rows_ok_csv" --json "$json"
fi
# The default scene's passes, each step of the splat timed on its own (--pass-timings):
# where a frame's time goes, on the compute path and at the thesis' viewport (times the
# scale). A second or two on a GPU.
if ((budget_spent)); then
  log "pass timings: skipped (time budget spent)"
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' pass-timings "" forward budget "" 0 "" "" "" "" >>"$runs"
else
  side="$(python3 -c "print(max(16, round(768 * $scale)))")"
  log "pass timings: render --pass-timings, the default scene at ${side}², sweep=compute"
  run pass-timings "" forward "$work/pass-timings.exr" \
    "$bin" render --device "$dev_index" --width "$side" --height "$side" --variant sweep=compute \
    --pass-timings -o "$work/pass-timings.exr"
fi
used_s=$(($(date +%s) - t_start))
finished_utc="$(date -u +%Y-%m-%dT%H:%M:%SZ)"
log "bench invocations took ${used_s} s of the ${budget} s budget"

# --- 4. The report ----------------------------------------------------------------------

commit=""; dirty=""
if command -v git >/dev/null 2>&1 && git -c safe.directory='*' rev-parse HEAD >/dev/null 2>&1; then
  commit="$(git -c safe.directory='*' rev-parse HEAD)"
  if [ -n "$(git -c safe.directory='*' status --porcelain --untracked-files=no 2>/dev/null)" ]; then dirty=true; else dirty=false; fi
elif [ -f .git/HEAD ]; then
  ref="$(sed -n 's/^ref: //p' .git/HEAD)"
  if [ -n "$ref" ] && [ -f ".git/$ref" ]; then commit="$(cat ".git/$ref")"
  elif [ -z "$ref" ]; then commit="$(cat .git/HEAD)"; fi
fi

log "step 4/4: writing $out_dir/$base.json and .md"
export GB_WORK="$work" GB_RUNS="$runs" GB_OUT_JSON="$out_dir/$base.json" GB_OUT_MD="$out_dir/$base.md" \
  GB_ROOT="$root" GB_DATE="$date_utc" GB_STARTED="$started_utc" GB_FINISHED="$finished_utc" \
  GB_COMMIT="$commit" GB_DIRTY="$dirty" GB_DEV_NAME="$dev_name" GB_DEV_TYPE="$dev_type" \
  GB_DEV_INDEX="$dev_index" GB_DEV_VULKAN="$dev_vulkan" GB_DEV_DRIVER="$dev_driver" \
  GB_NVSMI="$nvsmi" GB_SCALE="$scale" GB_FRAMES="$frames" GB_WARMUP="$warmup" \
  GB_BUDGET="$budget" GB_USED="$used_s" GB_ROWS="$rows_csv" GB_ALLOW_CPU="$allow_cpu" \
  GB_STANDINS="$standin_dir" GB_MIN_START="$min_start_s"
python3 - <<'PY'
import json, os, sys

E = os.environ
root = E["GB_ROOT"]

def rel(p):
    return os.path.relpath(p, root) if p and p.startswith(root + "/") else p

def num(s):
    return float(s) if "." in s else int(s)

# The invocations, in order.
invocations = []
with open(E["GB_RUNS"]) as f:
    for line in f:
        kind, rows, transport, status, rc, elapsed, js, logf, new, cmd = line.rstrip("\n").split("\t")
        inv = {
            "kind": kind,
            "rows": rows.split(",") if rows else [],
            "light_transport": transport or None,
            "status": status,
            "exit_code": int(rc) if rc else None,
            "elapsed_s": int(elapsed),
            "standins_generated": new.split() if new else [],
            "command": cmd or None,
            "report_path": rel(js) if js and os.path.exists(js) else None,
            "log_path": rel(logf) if logf else None,
            "report": None,
        }
        if status == "ok" and kind == "pass-timings":
            # render's own lines, from "GPU time of the frame" on.
            with open(logf) as lf:
                text = lf.read()
            at = text.find("GPU time of the frame")
            text = text[at:] if at >= 0 else text
            # Not the "wrote <absolute path>" line: the image stays in the work folder.
            kept = [l for l in text.strip().splitlines() if not l.startswith("wrote ")]
            inv["report"] = {"pass_timings": "\n".join(kept)}
        elif status == "ok":
            with open(js) as jf:
                inv["report"] = json.load(jf)
        invocations.append(inv)

REASONS = {
    "ok": "ran",
    "budget": "time budget spent",
    "timeout": "timed out (the time budget ran out during the run)",
    "failed": "failed",
    "no-rows": "no row ran",
}

def reason(inv):
    r = REASONS.get(inv["status"], inv["status"])
    if inv["status"] == "failed":
        r += " (exit status %s%s; log %s)" % (inv["exit_code"], last_line(inv), inv["log_path"])
    return r

def last_line(inv):
    """The last non-empty line of a failed invocation's log, as ': line'."""
    try:
        with open(os.path.join(root, inv["log_path"]), errors="replace") as f:
            lines = [l.strip() for l in f if l.strip()]
    except (OSError, TypeError):
        return ""
    return (": " + lines[-1][:200]) if lines else ""

# Per row: status over its variants invocations.
rows_requested = E["GB_ROWS"].split(",")
rows_status = []
for row in rows_requested:
    invs = [v for v in invocations if v["kind"] == "variants" and v["rows"] == [row]]
    oks = [v for v in invs if v["status"] == "ok"]
    per_t = {}
    for v in invs:
        if v["light_transport"]:
            per_t[v["light_transport"]] = reason(v)
    bad = [v for v in invs if v["status"] != "ok"]
    if invs and not bad:
        st, why = "ran", None
    elif oks:
        st = "partial"
        why = "; ".join("%s %s" % (v["light_transport"], reason(v)) for v in bad)
    else:
        st = "not run"
        # A failure outranks a timeout, which outranks the budget.
        rank = {"failed": 0, "timeout": 1}
        worst = sorted(bad, key=lambda v: rank.get(v["status"], 2))[0] if bad else None
        why = reason(worst) if worst else "not run"
        if worst and worst["status"] == "failed" and worst["light_transport"]:
            why = "%s %s" % (worst["light_transport"], why)
    src = None
    for v in oks:
        for r in v["report"].get("rows", []):
            src = {
                "source": r.get("source"),
                "resolution": r.get("resolution"),
                "viewport": r.get("viewport"),
                "planes": r.get("planes"),
            }
    rows_status.append({
        "row": row,
        "status": st,
        "reason": why,
        "by_transport": per_t,
        "elapsed_s": sum(v["elapsed_s"] for v in invs),
        "standins_generated": [s for v in invs for s in v["standins_generated"]],
        "volume": src,
    })

# The summary: medians per row and transport.
def lever_map(levers):
    d = {}
    for kv in (levers or "").split(","):
        if "=" in kv:
            k, v = kv.split("=", 1)
            d[k.strip()] = v.strip()
    return d

def classify(var, pos):
    lv = lever_map(var.get("levers"))
    sweep, splat = lv.get("sweep"), lv.get("splat")
    if sweep == "compute" and lv.get("rays") == "all":
        return "compute_all_rays"
    if sweep == "compute" and lv.get("tile") not in (None, "off"):
        return "compute_tile"
    if sweep == "compute":
        return "compute"
    if sweep == "fragment" and splat == "compute":
        return "fragment_splat_compute"
    if sweep == "fragment":
        return "fragment"
    return ["compute", "fragment", "fragment_splat_compute"][pos] if pos < 3 else None

summary = []
for inv in invocations:
    if inv["kind"] != "variants" or inv["status"] != "ok":
        continue
    rep = inv["report"]
    transport = rep.get("settings", {}).get("light_transport") or inv["light_transport"]
    for r in rep.get("rows", []):
        line = {"row": r.get("dataset"), "light_transport": transport,
                "compute_ms": None, "fragment_ms": None, "fragment_splat_compute_ms": None,
                "compute_all_rays_ms": None, "compute_tile_ms": None}
        for pos, var in enumerate(r.get("variants", [])):
            c = classify(var, pos)
            if c:
                line[c + "_ms"] = var.get("stats", {}).get("median")
        c, fr = line["compute_ms"], line["fragment_ms"]
        line["compute_over_fragment"] = (c / fr) if (c is not None and fr) else None
        summary.append(line)

def fmt_ms(v):
    return "—" if v is None else ("%.2f" % v if v < 10000 else "%.0f" % v)

def fmt_ratio(v):
    return "—" if v is None else "%.3f" % v

table = [
    "| Row | Transport | sweep=compute ms | sweep=fragment ms | compute / fragment | sweep=fragment,splat=compute ms | sweep=compute,rays=all ms | sweep=compute,tile=on ms |",
    "|---|---|---:|---:|---:|---:|---:|---:|",
]
for s in summary:
    fwd = s["light_transport"] == "forward"
    table.append("| %s | %s | %s | %s | %s | %s | %s | %s |" % (
        s["row"], s["light_transport"], fmt_ms(s["compute_ms"]), fmt_ms(s["fragment_ms"]),
        fmt_ratio(s["compute_over_fragment"]),
        fmt_ms(s["fragment_splat_compute_ms"]) if fwd else "n/a",
        fmt_ms(s["compute_all_rays_ms"]) if fwd else "n/a",
        "n/a" if fwd else fmt_ms(s["compute_tile_ms"])))
if not summary:
    table.append("| (no row ran) | | | | | | | |")

# Baselines.
base_inv = next((v for v in invocations if v["kind"] == "thesis-baselines"), None)
base_lines = []
if base_inv and base_inv["status"] == "ok":
    rep = base_inv["report"]
    def med(r, k):
        v = r.get(k)
        return v["stats"]["median"] if isinstance(v, dict) and v.get("stats") else None
    base_lines += [
        "| Row | Sweep (refract) ms | EA ray marcher ms | Sweep floor ms | Skeleton ms | Sweep / EA | Sweep / floor | Sweep / skeleton |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rep.get("rows", []):
        base_lines.append("| %s | %s | %s | %s | %s | %s | %s | %s |" % (
            r.get("dataset"), fmt_ms(med(r, "refract")), fmt_ms(med(r, "ea")), fmt_ms(med(r, "floor")),
            fmt_ms(med(r, "skeleton")), fmt_ratio(r.get("sweep_over_ea")),
            fmt_ratio(r.get("sweep_over_floor")), fmt_ratio(r.get("sweep_over_skeleton"))))

# The refrakt build the reports came from.
build_commit = None
for v in invocations:
    if v["report"]:
        build_commit = v["report"].get("meta", {}).get("git_commit")
        break

nvsmi = E["GB_NVSMI"].strip()
nv = None
if nvsmi:
    first = nvsmi.splitlines()[0]
    parts = [p.strip() for p in first.split(",")]
    nv = {"name": parts[0], "driver_version": parts[1] if len(parts) > 1 else None, "raw": nvsmi}

with open(os.path.join(E["GB_WORK"], "refrakt-info.txt")) as f:
    info_text = f.read()

rows_run = [r["row"] for r in rows_status if r["status"] == "ran"]
rows_not_run = [{"row": r["row"], "status": r["status"], "reason": r["reason"]}
                for r in rows_status if r["status"] != "ran"]
generated = [(r["row"], r["standins_generated"]) for r in rows_status if r["standins_generated"]]
dirty = {"true": True, "false": False}.get(E["GB_DIRTY"])

report = {
    "schema": "refrakt-gpu-bench/1",
    "date": E["GB_DATE"],
    "started_utc": E["GB_STARTED"],
    "finished_utc": E["GB_FINISHED"],
    "git": {"commit": E["GB_COMMIT"] or None, "dirty": dirty, "refrakt_build": build_commit},
    "device": {
        "name": E["GB_DEV_NAME"],
        "type": E["GB_DEV_TYPE"],
        "index": int(E["GB_DEV_INDEX"]),
        "vulkan": E["GB_DEV_VULKAN"],
        "driver": E["GB_DEV_DRIVER"],
        "nvidia_smi": nv,
        "refrakt_info": info_text,
    },
    "settings": {
        "scale": num(E["GB_SCALE"]),
        "frames": int(E["GB_FRAMES"]),
        "warmup": int(E["GB_WARMUP"]),
        "budget_s": int(E["GB_BUDGET"]),
        "min_start_s": int(E["GB_MIN_START"]),
        "rows_requested": rows_requested,
        "variants": {
            "forward": ["sweep=compute", "sweep=fragment", "sweep=fragment,splat=compute",
                        "sweep=compute,rays=all"],
            "backward": ["sweep=compute", "sweep=fragment", "sweep=compute,tile=on"],
        },
        "allow_cpu": E["GB_ALLOW_CPU"] == "1",
    },
    "budget": {
        "budget_s": int(E["GB_BUDGET"]),
        "used_s": int(E["GB_USED"]),
        "note": "the budget counts every bench invocation, including the first-use generation "
                "of the stand-in volumes (cached in %s); not the build" % E["GB_STANDINS"],
    },
    "rows_run": rows_run,
    "rows_not_run": rows_not_run,
    "rows": rows_status,
    "summary": summary,
    "invocations": invocations,
}
with open(E["GB_OUT_JSON"], "w") as f:
    json.dump(report, f, indent=1)
    f.write("\n")

# The Markdown page.
md = []
dev = E["GB_DEV_NAME"]
md.append("# refrakt GPU benchmark: %s, %s" % (dev, E["GB_DATE"]))
md.append("")
md.append("Written by `scripts/gpu-bench.sh` (%s to %s UTC). Times are GPU timestamps of whole frames, "
          "in milliseconds; each figure is the median of the measured frames." % (
              E["GB_STARTED"].replace("T", " ").rstrip("Z"), E["GB_FINISHED"][11:].rstrip("Z")))
md.append("")
md.append("- **Device:** %s (%s, Vulkan %s, device index %s)" % (dev, E["GB_DEV_TYPE"], E["GB_DEV_VULKAN"], E["GB_DEV_INDEX"]))
drv = "%s (refrakt info)" % E["GB_DEV_DRIVER"]
if nv:
    drv += "; nvidia-smi: %s, driver %s" % (nv["name"], nv["driver_version"])
md.append("- **Driver:** " + drv)
c = E["GB_COMMIT"]
ctext = ("`%s`" % c) if c else "unknown (no git)"
if dirty:
    ctext += " with uncommitted changes"
if build_commit:
    ctext += " (the binary reports `%s`)" % build_commit
md.append("- **Commit:** " + ctext)
md.append("- **Settings:** scale %s, %s measured frame(s) after %s warm-up per row and variant, variants "
          "rendered interleaved in one process" % (E["GB_SCALE"], E["GB_FRAMES"], E["GB_WARMUP"]))
md.append("- **Time budget:** %s s for all bench invocations, %s s used. It includes the first-use "
          "generation of the stand-in volumes (cached in `%s`; a second run on the same machine skips it), "
          "not the build." % (E["GB_BUDGET"], E["GB_USED"], E["GB_STANDINS"].replace(os.environ.get("HOME", "\0"), "~")))
if E["GB_DEV_TYPE"] not in ("discrete GPU", "integrated GPU", "virtual GPU"):
    md.append("- **Warning:** the device is a %s, not a GPU (REFRAKT_BENCH_ALLOW_CPU=1): these figures say "
              "nothing about GPU performance." % E["GB_DEV_TYPE"])
md.append("")
md.append("## Summary")
md.append("")
md.append("Median frame ms per row and light transport. *compute / fragment* is the sweep=compute "
          "median over the sweep=fragment median: below 1 the compute path is faster. "
          "The last column is the fragment path with the atomic compute splat (forward transport only).")
md.append("")
md += table
md.append("")
md.append("## Rows")
md.append("")
md.append("| Row | Status | Volume | Viewport | Planes | Seconds (both transports) | Stand-in generated |")
md.append("|---|---|---|---|---:|---:|---|")
for r in rows_status:
    v = r["volume"] or {}
    res = v.get("resolution")
    vol = ("%s (%s)" % ("×".join(map(str, res)), "stand-in" if v.get("source") == "stand-in" else v.get("source"))) if res else "—"
    vp = v.get("viewport")
    st = r["status"] if r["status"] == "ran" else "%s: %s" % (r["status"], r["reason"])
    st = st.replace("|", "\\|")
    md.append("| %s | %s | %s | %s | %s | %s | %s |" % (
        r["row"], st, vol, "%s×%s" % tuple(vp) if vp else "—", v.get("planes") if v.get("planes") is not None else "—",
        r["elapsed_s"] if r["elapsed_s"] else "—", "yes" if r["standins_generated"] else ("no" if r["status"] != "not run" else "—")))
md.append("")
md.append("Rows run: %s. Not run: %s." % (
    ", ".join(rows_run) or "none",
    "; ".join("%s (%s)" % (r["row"], r["reason"] if r["status"] == "not run" else "partial: " + (r["reason"] or "")) for r in rows_not_run) or "none"))
md.append("")
md.append("## Baselines")
md.append("")
if base_inv and base_inv["status"] == "ok":
    md.append("`bench thesis --baselines` on the rows that ran, default levers (sweep=auto), transport %s; "
              "median frame ms, ratios of means as refrakt reports them:" % (
                  base_inv["report"].get("settings", {}).get("light_transport") or "forward"))
    md.append("")
    md += base_lines
else:
    md.append("Not run: %s." % (reason(base_inv) if base_inv else "no row ran"))
md.append("")
md.append("## Pass timings")
md.append("")
pt_inv = next((v for v in invocations if v["kind"] == "pass-timings"), None)
if pt_inv and pt_inv["status"] == "ok":
    md.append("The default scene with `render --pass-timings --variant sweep=compute` (GPU ms per "
              "frame, each per-plane pass summed over the planes):")
    md.append("")
    md.append("```")
    md.append(pt_inv["report"]["pass_timings"])
    md.append("```")
else:
    md.append("Not run: %s." % (reason(pt_inv) if pt_inv else "not reached"))
md.append("")
md.append("## Command lines")
md.append("")
md.append("From the repository root, in this order (each under `timeout` with the budget left):")
md.append("")
md.append("```")
for v in invocations:
    if v["command"]:
        md.append(v["command"])
md.append("```")
md.append("")
md.append("The full reports of these commands are embedded in `%s` (key `invocations`)." % os.path.basename(E["GB_OUT_JSON"]))
md.append("")
with open(E["GB_OUT_MD"], "w") as f:
    f.write("\n".join(md))

print("\n".join(table))
PY

log "wrote ${GB_OUT_JSON#"$root"/} and ${GB_OUT_MD#"$root"/}"
if ((${#rows_ok[@]} == 0)); then
  die "no row ran (see ${GB_OUT_MD#"$root"/})"
fi
