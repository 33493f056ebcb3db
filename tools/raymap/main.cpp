// SPDX-License-Identifier: BSD-3-Clause
// raymap command line (placeholder until the subcommands land in this change).
int main() { return 0; }
