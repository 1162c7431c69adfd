#!/bin/bash
# Installs the built tree into a temporary prefix (no rebuild) and checks it as a user would
# (docs/cli.md, "Installing"):
#   consumer  a project outside the tree finds the package (find_package(tomodem)), builds against
#             the installed headers and static libraries, and runs a Hertz collision (consumer/main.cpp)
#   man       every installed tool has a man page that names every option and subcommand its
#             --help lists, and a bash completion script that bash accepts and that offers them
# usage: install_test.sh consumer|man BUILD_DIR
set -euo pipefail
mode=$1
build=$2
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix
cmake --install "$build" --prefix "$prefix" >"$tmp/install.log" || { cat "$tmp/install.log"; exit 1; }

if [ "$mode" = consumer ]; then
  for f in lib/cmake/tomodem/tomodemConfig.cmake lib/cmake/tomodem/tomodemConfigVersion.cmake \
           lib/cmake/tomodem/tomodemTargets.cmake include/tomodem/dem/simulation.hpp include/tomodem/core/vec3.hpp \
           lib/libtomodem_dem.a lib/libtomodem_core.a bin/tomodem bin/tomodem-dem; do
    [ -e "$prefix/$f" ] || { echo "not installed: $f"; exit 1; }
  done
  # The consumer must not see the source tree: only the prefix is given.
  cmake -S "$here/consumer" -B "$tmp/consumer" -G Ninja -DCMAKE_BUILD_TYPE=Release \
        -DCMAKE_PREFIX_PATH="$prefix" >"$tmp/configure.log" 2>&1 || { cat "$tmp/configure.log"; exit 1; }
  if grep -q "$(cd "$here/../../.." && pwd)/libs" "$tmp/consumer/build.ninja"; then
    echo "the consumer build refers to the source tree's libs/"; exit 1
  fi
  cmake --build "$tmp/consumer" >"$tmp/build.log" 2>&1 || { cat "$tmp/build.log"; exit 1; }
  OMP_NUM_THREADS=1 "$tmp/consumer/collide"
  exit $?
fi

[ "$mode" = man ] || { echo "unknown mode $mode"; exit 2; }
checked=0
for exe in "$prefix"/bin/tomodem-*; do
  tool=$(basename "$exe")
  page=$prefix/share/man/man1/$tool.1
  comp=$prefix/share/bash-completion/completions/$tool
  [ -s "$page" ] || { echo "$tool: no man page $page"; exit 1; }
  [ -s "$comp" ] || { echo "$tool: no bash completion $comp"; exit 1; }
  # The page as text: troff's \- is '-', font changes dropped.
  text=$(sed -e 's/\\-/-/g' -e 's/\\f[BIRP]//g' "$page")
  grep -q "^\.TH ${tool^^} 1 " "$page" || { echo "$tool: no .TH header"; exit 1; }
  help=$("$exe" --help)
  # Options: the first words of the option lines (-o,--output TEXT); subcommands: the lines under "Subcommands:".
  opts=$(grep -oE '^ +-{1,2}[A-Za-z][A-Za-z0-9-]*(,-{1,2}[A-Za-z][A-Za-z0-9-]*)*' <<<"$help" | tr ',' '\n' | tr -d ' ')
  subs=$(awk '/^Subcommands:/{s=1; next} /^[^ ]/{s=0} s && NF {print $1}' <<<"$help")
  [ -n "$opts" ] || { echo "$tool: no options found in --help"; exit 1; }
  for o in $opts; do
    grep -qE -- "(^|[ ,])$o([ ,]|$)" <<<"$text" || { echo "$tool: the man page does not list $o"; exit 1; }
    if [[ $o == --* ]]; then
      grep -qE -- "(\"| )$o( |\")" "$comp" || { echo "$tool: the completion does not offer $o"; exit 1; }
    fi
  done
  for s in $subs; do
    grep -q "^\.SS $s" "$page" || { echo "$tool: the man page has no section for subcommand $s"; exit 1; }
  done
  bash -n "$comp" || { echo "$tool: the completion script is not valid bash"; exit 1; }
  # Sourced, it registers a completion for the tool.
  bash -c "source '$comp' && complete -p $tool" >/dev/null || { echo "$tool: the completion registers nothing"; exit 1; }
  checked=$((checked + 1))
done
[ "$checked" -ge 1 ] || { echo "no tools installed"; exit 1; }
echo "man pages and completions of $checked tools list every option of their --help"
