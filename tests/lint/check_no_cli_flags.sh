#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The library's messages name options by configuration key ("heightmap.size",
# "backend.fallback: cpu"), never by a command-line flag ("--size"): raymapd and library users
# never typed the flags, and `raymap` turns the keys into its own flags when it prints them
# (tools/raymap/option_names.cpp). This fails on any string literal in src/, include/ or kernels/
# holding "--" and a letter. Comments are not looked at.
#
# Allowed, each with its reason:
#   src/app/raymapd.cpp: raymapd's own command line (--config, --check-config, --version): its
#     front end, where the flags are the daemon's own.
set -euo pipefail
root=${1:-.}
cd "$root"
allowed=(
  src/app/raymapd.cpp
)
files=()
while IFS= read -r file; do
  skip=0
  for a in "${allowed[@]}"; do
    [ "$file" = "$a" ] && skip=1
  done
  [ "$skip" -eq 0 ] && files+=("$file")
done < <(find src include kernels -type f \( -name '*.cpp' -o -name '*.hpp' -o -name '*.h' \
  -o -name '*.cu' -o -name '*.cuh' -o -name '*.cl' \) | sort)
# Comments, string literals (raw ones included) and character literals, in the order they
# start: a "--" in a comment or in code (--i) is not a message.
perl -0777 -ne '
  my $text = $_;
  while ($text =~ m{ (//[^\n]*) | (/\*.*?\*/) | (R"([^(\s"]*)\((.*?)\)\4")
                   | ("(?:[^"\\\n]|\\.)*") | (\x27(?:[^\x27\\\n]|\\.)*\x27) }gsx) {
    my ($literal, $start) = (defined $3 ? $3 : $6, $-[0]);
    next unless defined $literal && $literal =~ /--[A-Za-z]/;
    my $line = 1 + (substr($text, 0, $start) =~ tr/\n//);
    print "$ARGV:$line: a library message names a command-line flag: $literal\n";
    $found = 1;
  }
  END { exit($found ? 1 : 0) }
' "${files[@]}" && exit 0
echo "Name the option by its configuration key instead (heightmap.size, backend.fallback: cpu;" \
  "docs/architecture.md, \"Messages name configuration keys\")." >&2
exit 1
