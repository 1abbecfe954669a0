#!/usr/bin/env bash
# A clone alone is the whole product: no code, build, script, test or doc file may reach outside the
# repository for a resource (the pattern is spelled in pieces so that this file does not match itself).
set -uo pipefail
src="$1"
cd "$src" || exit 2
pattern='\.\./'"shared"'|'"shared"'/models|'"shared"'/docs'
if git -C "$src" rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -t files < <(git ls-files --cached --others --exclude-standard)
else
  mapfile -t files < <(find . -type f -not -path './build*' -not -path './.git/*' | sed 's#^\./##')
fi
hits=()
for f in "${files[@]}"; do
  [ -f "$f" ] || continue
  case "$f" in
    *.cc|*.h|*.in|*.py|*.sh|*.cmake|CMakeLists.txt|*/CMakeLists.txt|Makefile|*Snakefile|*.smk|*.yaml|*.json|*.js|*.mjs|*.md|.ci/*) ;;
    *) continue ;;
  esac
  # Third-party model notes describe their own upstream layout.
  case "$f" in models/lpips/*) continue ;; esac
  if grep -nE "$pattern" "$f" >/dev/null; then hits+=("$f"); fi
done
if [ ${#hits[@]} -gt 0 ]; then
  echo "files that name a path outside the repository (the pattern above):"
  for f in "${hits[@]}"; do grep -nHE "$pattern" "$f"; done
  exit 1
fi
echo "checked ${#files[@]} files: none names a path outside the repository"
