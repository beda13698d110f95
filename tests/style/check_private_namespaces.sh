#!/usr/bin/env bash
# What a module keeps to itself lives in an anonymous namespace (one file) or in `detail` (several
# files of the module): one spelling, so a reader knows at once what is not the module's interface.
set -euo pipefail
cd "${1:?usage: check_private_namespaces.sh SOURCE_DIR}"

found=$(find . \( -path ./build -o -path ./.git \) -prune -o \( -name '*.cpp' -o -name '*.hpp' \) \
  -print | sed 's|^\./||' |
  xargs grep -nE 'namespace ([a-z_]+::)*(internal|impl|priv|private|[a-z]+_detail|detail_[a-z]+)\b' ||
  true)
if [ -n "$found" ]; then
  echo "private namespaces spelt otherwise than 'detail' or anonymous:"
  echo "$found"
  exit 1
fi
echo "check_private_namespaces: every private namespace is 'detail' or anonymous"
