#!/usr/bin/env bash
# Validates a sample configuration with the real daemon: `--config FILE
# --print-config` must exit 0 (the daemon parsed every key with its type),
# print each expected line, and print a configuration that loads back to
# the same text (the printed TOML is a fixed point).
# Usage: check_config.sh "DAEMON [SUBCOMMAND]" CONFIG 'EXPECTED LINE'...
set -euo pipefail
read -r -a command <<<"$1"
config=$2
shift 2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

if ! "${command[@]}" --config "$config" --print-config >"$tmp/first.toml" 2>"$tmp/err"; then
  echo "FAIL: ${command[*]} --config $config --print-config exited non-zero:" >&2
  cat "$tmp/err" >&2
  exit 1
fi
status=0
for line in "$@"; do
  if ! grep -qxF -- "$line" "$tmp/first.toml"; then
    echo "FAIL: expected line '$line' not in the effective configuration" >&2
    status=1
  fi
done
"${command[@]}" --config "$tmp/first.toml" --print-config >"$tmp/second.toml"
if ! cmp -s "$tmp/first.toml" "$tmp/second.toml"; then
  echo "FAIL: the printed configuration does not load back to itself:" >&2
  diff "$tmp/first.toml" "$tmp/second.toml" >&2 || true
  status=1
fi
((status == 0)) && echo "OK: $config ($(wc -l <"$tmp/first.toml") lines, $# expected lines found)"
exit "$status"
