#!/usr/bin/env bash
# One command from a fresh Debian 12 machine to the running viewer on the default scene:
# installs missing packages, builds (Release) and starts softbody. Extra arguments go to softbody.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/install-deps.sh"
cmake -S "$root" -B "$root/build/release" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$root/build/release" -j"$(nproc)" --target softbody
exec "$root/build/release/app/softbody" "$@"
