#!/usr/bin/env bash
# Checks or applies the C++ style of .clang-format (clang-format from Debian's clang-format package)
# on the repository's C++ sources (tracked *.cpp, *.h, *.hpp; lcmtypes' generated code is not tracked).
#
#   scripts/format.sh [--check | --apply] [PATH ...]
#
# --check (default): changes nothing; lists each file clang-format would change with the number of
# lines that differ, then the totals; exit 1 when any file would change, 0 when none.
# --apply: rewrites the files in place. PATH limits either mode to files or folders.
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
MODE=check
PATHS=()
while [ $# -gt 0 ]; do
  case "$1" in
    --check) MODE=check; shift ;;
    --apply) MODE=apply; shift ;;
    -h|--help) awk 'NR == 1 { next } !/^#/ { exit } { sub(/^# ?/, ""); print }' "$0"; exit 0 ;;
    -*) echo "format.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
    *) PATHS+=("$1"); shift ;;
  esac
done
command -v clang-format > /dev/null || { echo "format.sh: clang-format not found (apt-get install clang-format)" >&2; exit 1; }
cd "$ROOT"
mapfile -t FILES < <(git ls-files -- "${PATHS[@]:-.}" | grep -E '\.(cpp|h|hpp)$' || true)
[ "${#FILES[@]}" -gt 0 ] || { echo "format.sh: no C++ file under ${PATHS[*]:-.}" >&2; exit 2; }
if [ "$MODE" = apply ]; then
  clang-format --style=file -i "${FILES[@]}"
  echo "format.sh: formatted ${#FILES[@]} files"
  exit 0
fi
changed=0; lines=0
for f in "${FILES[@]}"; do
  n=$(clang-format --style=file "$f" | diff "$f" - | grep -c '^[<>]' || true)
  if [ "$n" -gt 0 ]; then
    echo "$f: $n lines differ"
    changed=$((changed + 1)); lines=$((lines + n))
  fi
done
echo "format.sh: $changed of ${#FILES[@]} files would change ($lines diff lines, old and new counted)"
[ "$changed" = 0 ]
