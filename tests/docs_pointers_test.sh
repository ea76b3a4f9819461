#!/usr/bin/env bash
# Checks the sources' pointers into docs/ (ctest DocsPointers, label unit):
#   1. every `docs/<name>.md` mentioned in a source file exists;
#   2. every `docs/<name>.md section N` names a numbered heading ("## N. ...") of that file;
#   3. no source file mentions the old design notes file (DESIGN dot md), which is not part of
#      the repository (the architecture notes are docs/ARCHITECTURE.md).
# Source files: *.h, *.cc, *.md, *.sh and CMakeLists.txt; in a git checkout the tracked and
# untracked files that git does not ignore (so build folders are skipped), else every such file
# outside build*/ folders and .git/.
# Usage: docs_pointers_test.sh [ROOT]   (default: the checkout this script is in)
# Prints FILE:LINE: PROBLEM for each offence and exits 1 when there is any.
set -euo pipefail

root=${1:-"$(dirname "$0")/.."}
root=$(cd "$root" && pwd -P)
cd "$root"

files=()
if command -v git >/dev/null 2>&1 &&
   [ "$(git -C "$root" rev-parse --show-toplevel 2>/dev/null || true)" = "$root" ]; then
  while IFS= read -r -d '' file; do files+=("$file"); done \
    < <(git -C "$root" ls-files -z -c -o --exclude-standard)
else
  while IFS= read -r -d '' file; do files+=("${file#./}"); done \
    < <(find . -type d \( -name 'build*' -o -name .git \) -prune -o -type f -print0)
fi

sources=()
for file in "${files[@]}"; do
  [ -f "$file" ] || continue  # tracked but deleted in the working tree
  case "$file" in
    *.h | *.cc | *.md | *.sh | CMakeLists.txt | */CMakeLists.txt) sources+=("$file") ;;
  esac
done
if [ ${#sources[@]} -eq 0 ]; then
  echo "docs_pointers_test: no source files found under $root" >&2
  exit 1
fi

failures=0
fail() {
  echo "$1: $2"
  failures=$((failures + 1))
}

# 1 and 2: pointers into docs/. grep prints FILE:LINE:MATCH, one match per line.
while IFS= read -r hit; do
  location=${hit%:*}         # FILE:LINE
  pointer=${hit##*:}         # docs/<name>.md[ section N]
  doc=${pointer%%.md*}.md
  if [ ! -f "$doc" ]; then
    fail "$location" "$doc does not exist"
    continue
  fi
  if [[ $pointer =~ section\ ([0-9]+)$ ]]; then
    section=${BASH_REMATCH[1]}
    grep -qE "^#{1,6} $section\. " "$doc" || fail "$location" "$doc has no section $section (no heading \"## $section. ...\")"
  fi
done < <(grep -nHoE 'docs/[A-Za-z0-9_./-]+\.md(,? section [0-9]+)?' -- "${sources[@]}" || true)

# 3: the old design notes (the name is split so that this script does not mention it).
old_notes="DESIGN"".md"
while IFS= read -r hit; do
  line=${hit#*:}
  fail "${hit%%:*}:${line%%:*}" "mentions $old_notes, which is not in the repository; point to docs/ARCHITECTURE.md (and its section) instead"
done < <(grep -nHF "$old_notes" -- "${sources[@]}" || true)

if [ "$failures" -gt 0 ]; then
  echo "docs_pointers_test: $failures bad pointer(s) in ${#sources[@]} source files under $root"
  exit 1
fi
echo "docs_pointers_test: ${#sources[@]} source files under $root, every docs/ pointer resolves"
