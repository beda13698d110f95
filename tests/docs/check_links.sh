#!/usr/bin/env bash
# Every relative link of every Markdown file in the repository, and every docs/*.md (or module
# README) the code cites, names a file that exists: a user who clones the repository has nothing
# else to read.
set -euo pipefail
cd "${1:?usage: check_links.sh SOURCE_DIR}"

broken=0
while IFS= read -r md; do
  dir=$(dirname "$md")
  # [text](target) links outside code spans; external ones (scheme:) and in-page anchors (#...)
  # are not files.
  while IFS= read -r target; do
    target=${target%%#*}
    [ -z "$target" ] && continue
    case "$target" in *://* | mailto:*) continue ;; esac
    if [ ! -e "$dir/$target" ]; then
      echo "$md: link to $target: no such file"
      broken=$((broken + 1))
    fi
  done < <(sed 's/`[^`]*`//g' "$md" | grep -o '\](\([^)]*\))' | sed 's/^](\(.*\))$/\1/' || true)
done < <(git ls-files '*.md')

while IFS= read -r hit; do
  file=${hit%%:*}
  cited=$(printf '%s\n' "${hit#*:}" | grep -o 'docs/[A-Za-z0-9_./-]*\.md' || true)
  for doc in $cited; do
    if [ ! -e "$doc" ]; then
      echo "$file cites $doc: no such file"
      broken=$((broken + 1))
    fi
  done
done < <(git grep -n 'docs/[A-Za-z0-9_./-]*\.md' -- '*.cpp' '*.hpp' '*.cmake' 'CMakeLists.txt' '*.sh' '*.toml' || true)

if [ "$broken" -ne 0 ]; then
  echo "check_links: $broken broken"
  exit 1
fi
echo "check_links: every link and cited doc exists"
