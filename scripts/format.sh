#!/usr/bin/env bash
# clang-format (the project's .clang-format) on the C++ lines that changed since a commit: the tree
# as a whole has never been formatted, so a whole-tree run would rewrite code other branches are
# changing; only what a change touches is held to the format.
#
#   scripts/format.sh --since REV           formats, in place, the changed lines of the work tree
#   scripts/format.sh --check --since REV   changes nothing; prints the diff clang-format wants and
#                                           fails when there is one (CI: .ci/run, with the commit
#                                           of .ci/format-clean)
#
# "Changed" is `git diff -U0 REV` of the work tree (committed and uncommitted changes): a new file
# is all changed lines, a moved block is changed where git says it is. The lines are handed to
# clang-format-diff, which formats whole statements around them.
set -euo pipefail
cd "$(dirname "$0")/.."
check=0
since=""
while [[ $# -gt 0 ]]; do
  case $1 in
    --check) check=1 ;;
    --since) since=${2:?"format.sh: --since needs a commit"}; shift ;;
    *) echo "format.sh: unknown argument '$1' (expected --check, --since REV)" >&2; exit 2 ;;
  esac
  shift
done
if [[ -z $since ]]; then
  echo "format.sh: --since REV is required (a whole-tree format is the lead's decision, not this script's)" >&2
  exit 2
fi
if ! git rev-parse --verify --quiet "$since^{commit}" >/dev/null; then
  echo "format.sh: '$since' is not a commit of this repository" >&2
  exit 2
fi

scripts/install-deps.sh tidy >/dev/null
# Debian ships the script as clang-format-diff (and clang-format-diff-14).
cfd=$(command -v clang-format-diff || command -v clang-format-diff-14 || true)
if [[ -z $cfd ]]; then
  echo "format.sh: clang-format-diff not found (package clang-format)" >&2
  exit 2
fi

# tests/data/ holds fixtures (trees of the layering and docs checks), not compiled as C++ of the project.
paths=('*.cpp' '*.hpp' '*.h' '*.cc' ':!tests/data/')
diff=$(git diff -U0 --no-color --relative "$since" -- "${paths[@]}")
# New files that are not staged yet are not in `git diff`: add them whole.
untracked=$(git ls-files --others --exclude-standard -- "${paths[@]}")
if [[ -n $untracked ]]; then
  while IFS= read -r f; do
    diff+=$'\n'$(git diff -U0 --no-color --no-index /dev/null "$f" || true)
  done <<<"$untracked"
fi
# grep, not ${diff//...}: bash's pattern substitution is quadratic, minutes on a 1.5 MB diff.
if ! grep -q . <<<"$diff"; then
  echo "format: no C++ line changed since $since"
  exit 0
fi

if [[ $check -eq 0 ]]; then
  "$cfd" -p1 -i <<<"$diff"
  echo "format: formatted the C++ lines changed since $since"
  exit 0
fi
wanted=$("$cfd" -p1 <<<"$diff")
if [[ -n $wanted ]]; then
  printf '%s\n' "$wanted"
  files=$(grep -c '^+++ ' <<<"$wanted" || true)
  echo "format: $files files have changed lines that clang-format would change (scripts/format.sh --since $since formats them)" >&2
  exit 1
fi
echo "format: the C++ lines changed since $since are formatted"
