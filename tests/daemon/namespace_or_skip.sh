# Sourced by the tests that re-run themselves in namespaces of their own (unshare): defines
# namespace_or_skip, which exits 77 (ctest: skipped), saying why, where a tool is missing or the
# namespaces are not permitted.
# usage: namespace_or_skip UNSHARE_FLAGS TOOL...
namespace_or_skip() {
  local flags=$1
  shift
  local tool
  for tool in "$@"; do
    if ! command -v "$tool" >/dev/null 2>&1; then
      echo "SKIP: needs $tool"
      exit 77
    fi
  done
  if ! unshare "$flags" true >/dev/null 2>&1; then
    echo "SKIP: unshare $flags is not permitted here (no user namespace, or not the ones it asks for)"
    exit 77
  fi
}
