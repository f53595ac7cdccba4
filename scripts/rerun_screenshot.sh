#!/usr/bin/env bash
# A screenshot of a recording in Rerun's web viewer, under headless Chromium (how
# docs/rerun_impact_coarse.png is made):
#   regolith run scenes/impact_tipped_coarse.ron --rrd run.rrd
#   scripts/rerun_screenshot.sh out/impact_tipped_coarse/run.rrd docs/rerun_impact_coarse.png
# Needs `rerun` (pip install rerun-sdk==0.36.3, the version the recorder is built with),
# Debian's chromium, and playwright-core from npm (`npm install playwright-core` in a
# directory whose node_modules NODE_PATH names).
set -euo pipefail
rrd=${1:?usage: scripts/rerun_screenshot.sh RECORDING.rrd OUT.png [SECONDS]}
png=${2:?usage: scripts/rerun_screenshot.sh RECORDING.rrd OUT.png [SECONDS]}
wait_s=${3:-40}
log=$(mktemp)
profile=$(mktemp -d)
# The viewer's own config and the browser profile stay out of the user's home.
export XDG_CONFIG_HOME="$profile/config" XDG_DATA_HOME="$profile/data"
rerun "$rrd" --web-viewer --web-viewer-port 9090 --port 9876 --hide-welcome-screen >"$log" 2>&1 &
server=$!
# The pip-installed `rerun` is a launcher that starts the viewer as its child: stop both.
trap 'pkill -P $server 2>/dev/null; kill $server 2>/dev/null; rm -rf "$profile" "$log"' EXIT
for _ in $(seq 50); do
    grep -q "127.0.0.1:9090\|localhost:9090\|0.0.0.0:9090" "$log" && break
    sleep 0.2
done
url="http://127.0.0.1:9090/?url=rerun%2Bhttp%3A%2F%2F127.0.0.1%3A9876%2Fproxy"
node "$(dirname "$0")/rerun_screenshot.cjs" "$url" "$png" "$wait_s"
echo "wrote $png"
