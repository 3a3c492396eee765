#!/usr/bin/env bash
# Installs the build tree into a fresh temporary prefix and checks the result:
# - the installed files are exactly the expected list (no library, header,
#   test or benchmark slips in);
# - each installed unit's ExecStart names /usr/local/BINDIR/<daemon> (the
#   documented `--prefix /usr/local`) and /etc/thinlod/<daemon>.toml;
# - each daemon needs no library from the build tree (ldd, RUNPATH) and the
#   command of its unit runs `--help` with exit 0, listing --config.
# Usage: install_test.sh CMAKE BUILD_DIR BINDIR DATADIR DOCDIR (the last three
# relative to the prefix, as GNUInstallDirs gives them).
set -euo pipefail
cmake=$1 build=$2 bindir=$3 datadir=$4 docdir=$5
for dir in "$bindir" "$datadir" "$docdir"; do
  case $dir in /*) echo "FAIL: install dir '$dir' is absolute; expected relative to the prefix"; exit 1 ;; esac
done

work=$(mktemp -d "${TMPDIR:-/tmp}/thinlod-install.XXXXXX")
trap 'rm -rf "$work"' EXIT
prefix=$work/prefix
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

echo "check: cmake --install $build --prefix $prefix exits 0"
if ! "$cmake" --install "$build" --prefix "$prefix" >"$work/install.log" 2>&1; then
  cat "$work/install.log"
  echo "FAIL: cmake --install exited non-zero"; exit 1
fi

daemons=(backbone simplifier frontend)
expected=("$docdir/deployment.md" "$datadir/thinlod/systemd/thinlod.sysusers.conf")
for d in "${daemons[@]}"; do
  expected+=("$bindir/thinlod-$d" "$datadir/thinlod/systemd/thinlod-$d.service"
             "$datadir/thinlod/examples/$d.toml")
done
expected+=("$bindir/thinlod-keys")  # CURVE key pairs (docs/deployment.md, "Keys")
wanted=$(printf '%s\n' "${expected[@]}" | sort)
echo "check: the installed files are exactly these ${#expected[@]}:"
echo "$wanted" | sed 's/^/  /'
actual=$(cd "$prefix" && find . -type f -o -type l | sed 's|^\./||' | sort)
if [[ "$actual" != "$wanted" ]]; then
  fail "installed file list differs (< expected, > installed):"
  diff <(echo "$wanted") <(echo "$actual") || true
fi

echo "check: the installed thinlod-keys writes a key pair it can load back"
if ! "$prefix/$bindir/thinlod-keys" --dir "$work" installed-test >/dev/null ||
   ! "$prefix/$bindir/thinlod-keys" --check "$work/installed-test.key" >/dev/null; then
  fail "installed thinlod-keys could not write or load a key pair"
fi
if ldd "$prefix/$bindir/thinlod-keys" | grep -qF "$build"; then
  fail "thinlod-keys loads a library from the build tree"
fi

for d in "${daemons[@]}"; do
  exe="$prefix/$bindir/thinlod-$d"
  unit="$prefix/$datadir/thinlod/systemd/thinlod-$d.service"
  echo "check: thinlod-$d: unit ExecStart, no build-tree library or RPATH, --help exits 0"
  if [[ ! -x "$exe" ]]; then fail "$exe missing or not executable"; continue; fi
  if [[ ! -f "$unit" ]]; then fail "$unit missing"; continue; fi

  # ExecStart=/usr/local/bin/thinlod-simplifier serve --config /etc/thinlod/simplifier.toml
  read -r -a exec_start <<<"$(sed -n 's/^ExecStart=//p' "$unit")"
  if [[ "${exec_start[0]:-}" != "/usr/local/$bindir/thinlod-$d" ]]; then
    fail "$unit: ExecStart runs '${exec_start[0]:-}', not /usr/local/$bindir/thinlod-$d"
  fi
  if [[ " ${exec_start[*]} " != *" --config /etc/thinlod/$d.toml "* ]]; then
    fail "$unit: ExecStart does not read /etc/thinlod/$d.toml: ${exec_start[*]}"
  fi
  subcommand=()
  [[ "${exec_start[1]:-}" != --* && -n "${exec_start[1]:-}" ]] && subcommand=("${exec_start[1]}")

  if ldd "$exe" | grep -q "not found"; then
    fail "thinlod-$d has unresolved libraries:"; ldd "$exe" | grep "not found" || true
  fi
  if ldd "$exe" | grep -qF "$build"; then
    fail "thinlod-$d loads a library from the build tree:"; ldd "$exe" | grep -F "$build" || true
  fi
  runpath=$(readelf -d "$exe" | grep -E 'R(UN)?PATH' || true)
  if [[ "$runpath" == *"$build"* ]]; then fail "thinlod-$d keeps a build-tree RPATH: $runpath"; fi

  command_line="$bindir/thinlod-$d ${subcommand[*]:+${subcommand[*]} }--help"
  echo "  run: $command_line"
  if ! help=$(cd "$work" && "$exe" "${subcommand[@]}" --help 2>&1); then
    fail "$command_line exited non-zero:"; echo "$help" | head -20
  elif [[ "$help" != *"--config"* ]]; then
    fail "$command_line does not list --config:"; echo "$help" | head -20
  fi
done

if ((failures > 0)); then
  echo "install test: $failures failure(s)"; exit 1
fi
echo "install test: all checks passed"
