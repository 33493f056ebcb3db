# SPDX-License-Identifier: BSD-3-Clause
# The device kit's record of what it measured (sourced by run.sh). Every section appends JSON
# objects and Markdown lines to files in $work; publish_results rewrites the results folder after
# every section, so a run stopped by its time limit still returns everything measured before.
# Plain bash, coreutils, grep, sed and awk only: the kit runs on a bare machine.

# json_string TEXT: TEXT as a JSON string literal (control characters dropped).
json_string() {
  local s
  s=$(printf '%s' "$1" | tr -d '\000-\010\013\014\016-\037')
  s=${s//\\/\\\\}
  s=${s//\"/\\\"}
  s=${s//$'\n'/\\n}
  s=${s//$'\t'/\\t}
  s=${s//$'\r'/}
  printf '"%s"' "$s"
}

# json_number TEXT: TEXT when it is a JSON number, else null (a value a run did not produce).
json_number() {
  if [[ $1 =~ ^-?[0-9]+(\.[0-9]+)?([eE][-+]?[0-9]+)?$ ]]; then printf '%s' "$1"; else printf 'null'; fi
}

# number KEY FILE [N]: like value (tools/bench/bench-lib.sh), but 0 when there is none (sums).
number() {
  local v=""
  [ -f "$2" ] && v=$(value "$@")
  echo "${v:-0}"
}

# ratio A B [FORMAT]: A / B, empty when either is missing or B is zero.
ratio() {
  awk -v a="$1" -v b="$2" -v f="${3:-%.2f}" \
    'BEGIN { if (a == "" || b == "" || b + 0 == 0) exit; printf f, a / b }'
}

# record SECTION JSON_OBJECT: one result of a section, in results.json's "SECTION" list.
record() {
  printf '%s\n' "$2" >>"$work/json/$1.jsonl"
}

# md SECTION LINE...: lines of a section's part of results.md.
md() {
  local section=$1
  shift
  printf '%s\n' "$@" >>"$work/md/$section.md"
}

# fail WHAT: a check failed (the run exits 1); noted in both results files.
fail() {
  printf '%s\n' "$1" >>"$work/failures"
  log "FAIL: $1"
}

# note WHAT: something the reader must know that is not a failure (a skip, a missing tool).
note() {
  printf '%s\n' "$1" >>"$work/notes"
  log "note: $1"
}

# log LINE: to the terminal and run.log, with the seconds since the start.
log() {
  printf '[%4ds] %s\n' "$(elapsed)" "$1" | tee -a "$out/run.log" >&2
}

elapsed() { echo $((SECONDS - started)); }

# remaining: seconds left of the run's budget.
remaining() { echo $((budget - SECONDS + started)); }

# jsonl_array FILE: the objects of a .jsonl file as a JSON array.
jsonl_array() {
  if [ -s "$1" ]; then
    printf '[\n'
    sed '$!s/$/,/; s/^/    /' "$1"
    printf '  ]'
  else
    printf '[]'
  fi
}

# lines_array FILE: the lines of a file as a JSON array of strings.
lines_array() {
  local first=1 line
  printf '['
  if [ -s "$1" ]; then
    while IFS= read -r line; do
      [ $first = 1 ] || printf ', '
      first=0
      json_string "$line"
    done <"$1"
  fi
  printf ']'
}

# publish_results: results.md, results.json and logs.tar.gz in $out, from what is recorded so far.
publish_results() {
  local section status
  status=$(run_status)
  {
    echo "# raymap device kit: results"
    echo
    echo "- kit: $(kit_field commit) built $(kit_field built) (nvcc $(kit_field nvcc), CUDA architectures $(kit_field cuda_architectures))"
    echo "- machine: $cpu_model, $(nproc) cores; GPU: ${gpu_name:-none}${gpu_driver:+, driver $gpu_driver}"
    echo "- status: **$status** after $(elapsed) s of a $budget s budget"
    if [ -s "$work/failures" ]; then
      echo "- failures:"
      sed 's/^/  - /' "$work/failures"
    fi
    if [ -s "$work/notes" ]; then
      echo "- notes:"
      sed 's/^/  - /' "$work/notes"
    fi
    for section in "${all_sections[@]}"; do
      if [ -s "$work/md/$section.md" ]; then
        echo
        cat "$work/md/$section.md"
      fi
    done
  } >"$out/results.md.tmp" && mv "$out/results.md.tmp" "$out/results.md"
  {
    printf '{\n  "kit": {"commit": %s, "built": %s, "nvcc": %s, "cuda_architectures": %s},\n' \
      "$(json_string "$(kit_field commit)")" "$(json_string "$(kit_field built)")" \
      "$(json_string "$(kit_field nvcc)")" "$(json_string "$(kit_field cuda_architectures)")"
    printf '  "machine": {"cpu_model": %s, "cores": %s, "gpu": %s, "driver": %s},\n' \
      "$(json_string "$cpu_model")" "$(nproc)" "$(json_string "${gpu_name:-}")" \
      "$(json_string "${gpu_driver:-}")"
    printf '  "status": %s,\n  "seconds": %s,\n  "budget_seconds": %s,\n' \
      "$(json_string "$status")" "$(elapsed)" "$budget"
    printf '  "failures": %s,\n  "notes": %s' "$(lines_array "$work/failures")" \
      "$(lines_array "$work/notes")"
    for section in "${json_lists[@]}"; do
      printf ',\n  "%s": %s' "$section" "$(jsonl_array "$work/json/$section.jsonl")"
    done
    printf '\n}\n'
  } >"$out/results.json.tmp" && mv "$out/results.json.tmp" "$out/results.json"
  tar -czf "$out/logs.tar.gz.tmp" -C "$work" logs 2>/dev/null &&
    mv "$out/logs.tar.gz.tmp" "$out/logs.tar.gz"
}

# run_status: passed, failed, or no CUDA device (CPU parts passed).
run_status() {
  if [ -s "$work/failures" ]; then
    echo "failed"
  elif [ "$have_cuda" = 1 ]; then
    echo "passed"
  else
    echo "no CUDA device (CPU parts passed)"
  fi
}

# kit_field KEY: a line "KEY: value" of the kit's KIT.txt.
kit_field() {
  sed -n "s/^$1: //p" "$kit/KIT.txt" 2>/dev/null | head -1
}
