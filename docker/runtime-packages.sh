#!/usr/bin/env bash
# Prints, one a line, the Debian packages that own the shared libraries the given binaries
# load: what the runtime image must install, read off the build instead of kept by hand.
set -euo pipefail
if missing=$(for bin in "$@"; do ldd "$bin"; done | grep "=> not found"); then
  echo "runtime-packages: unresolved libraries:" >&2
  echo "$missing" >&2
  exit 1
fi
for bin in "$@"; do ldd "$bin"; done | awk '$2 == "=>" && $3 ~ /^\// {print $3}' | sort -u |
  while read -r lib; do
    # usrmerge: ldd may name /lib/... while dpkg recorded /usr/lib/..., or the reverse.
    owner=$(dpkg -S "$lib" 2>/dev/null || dpkg -S "/usr$lib" 2>/dev/null ||
            dpkg -S "$(readlink -f "$lib")" 2>/dev/null || true)
    if [ -z "$owner" ]; then
      echo "runtime-packages: no package owns $lib" >&2
      exit 1
    fi
    echo "${owner%%:*}"
  done | sort -u
