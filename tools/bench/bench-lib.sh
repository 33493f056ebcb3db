#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Shared by the benchmark scripts (sourced): reading numbers out of the JSON that `raymap bench`
# and `raymap-octomap` print, the machine line of a summary, and the list of shared data sets.

value() {  # value KEY FILE [occurrence]: the number after "KEY": in a JSON file
  grep -o "\"$1\": [0-9.e+-]*" "$2" | sed -n "${3:-1}p" | awk '{print $2}'
}

text() {  # text KEY FILE: the first string value of KEY
  grep -o "\"$1\": \"[^\"]*\"" "$2" | head -1 | cut -d'"' -f4
}

machine_line() {  # machine_line EXTRA: commit, CPU model and cores, for a summary's first line
  echo "commit $(git rev-parse --short HEAD), $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) cores, $*"
}

run_data_sets() {  # run_data_sets FUNCTION DATA_DIR: FUNCTION NAME INPUT [options] per data set
  "$1" ouster "$2/ouster/ouster_os1_lb_n3_raycloud.ply.gz"
  "$1" 3dtk "$2/3dtk/3dtk_raycloud.ply.gz"
  "$1" 3dtk-points "$2/3dtk/3dtk_points.ply.gz" --trajectory "$2/3dtk/3dtk_trajectory.txt"
  "$1" octomap "$2/octomap/octomap_scan_raycloud.ply.gz"
}
