#!/usr/bin/env bash
# The man pages show the help text's non-ASCII characters (m³, θ, °, ≥) as they are, never as "?"
# (help2man in a non-UTF-8 locale wrote "??" for each; issue #29). For every page in MAN_DIR: the page
# has no "??", and each non-ASCII character of `APP --help` and `APP --help-config` is in the page.
# Usage: test_man_pages.sh MAN_DIR APP_EXE...
set -euo pipefail
man_dir=$1
shift
export LC_ALL=C.UTF-8
fail=0
for exe in "$@"; do
  app=$(basename "$exe")
  page=$man_dir/$app.1
  [ -f "$page" ] || { echo "FAIL: no man page $page"; fail=1; continue; }
  if grep -n '??' "$page" >/dev/null; then
    echo "FAIL: $page has '??':"; grep -n '??' "$page" | head -5; fail=1
  fi
  chars=$({ "$exe" --help; "$exe" --help-config 2>/dev/null || true; } | grep -o -P '[^\x00-\x7F]' | sort -u || true)
  n=0
  for c in $chars; do
    n=$((n + 1))
    grep -q -F "$c" "$page" || { echo "FAIL: $page lacks '$c' of $app's help text"; fail=1; }
  done
  echo "$app: $n distinct non-ASCII characters in the help text, all in $app.1"
done
[ $fail -eq 0 ] && echo "man pages: ok"
exit $fail
