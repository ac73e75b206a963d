# Sourced by the tests/js runner scripts after `set -euo pipefail`, with the
# tinsmith binary and an output folder as $1 and $2: sets bin, out, here
# (tests/js) and root (the repository), refuses to run without
# tests/js/node_modules, and empties out.
bin=$1
out=$2
here=$(cd "$(dirname "${BASH_SOURCE[1]}")" && pwd)
root=$(cd "$here/../.." && pwd)
if [[ ! -d "$here/node_modules/gltf-validator" ]]; then
  echo "tests/js/node_modules is missing: run tools/setup.sh" >&2
  exit 1
fi
rm -rf "$out"
mkdir -p "$out"
