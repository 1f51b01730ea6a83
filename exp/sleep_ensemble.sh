#!/bin/bash
# How soon a scene falls asleep after its last impact, over an ensemble of time steps.
#
# Runs `contact_lab scene` with sleep on at N time steps spread over 1/60 ± 10⁻⁵ s (two at a
# time) and prints for each: the time step, the last particle impact (s; a particle's velocity
# changing by more than 0.5 m/s in one step), when every body was asleep (s; −1: not by T) and
# the state hash; then how many runs never slept, and the mean and largest gap from the last
# impact to all asleep over the others (issue 11's target: ≤ 1 s).
#
# usage: exp/sleep_ensemble.sh CONTACT_LAB SCENE.json [N=8] [T=15] [contact_lab options...]
#   e.g. exp/sleep_ensemble.sh build/release/exp/contact_lab assets/scenes/large.json 8 15
set -euo pipefail
if [ $# -lt 2 ]; then
  sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//'
  exit 2
fi
lab=$1
scene=$2
n=${3:-8}
T=${4:-15}
shift $(($# < 4 ? $# : 4))
[ -x "$lab" ] || { echo "sleep_ensemble: $lab: not an executable contact_lab" >&2; exit 2; }
[ -r "$scene" ] || { echo "sleep_ensemble: $scene: cannot read the scene" >&2; exit 2; }
case $n in '' | *[!0-9]* | 0 | 1) echo "sleep_ensemble: N must be an integer ≥ 2, got '$n'" >&2; exit 2 ;; esac
case $T in '' | *[!0-9.]*) echo "sleep_ensemble: T must be a number of seconds, got '$T'" >&2; exit 2 ;; esac

run() {  # time step → one line: dt, last particle impact, all asleep from, state hash
  "$lab" scene path="$scene" sleep=1 T="$T" dt="$1" every=1000000 "${@:2}" | tail -n 1 |
    sed -E "s/.*a particle's: ([0-9.e+-]+) s\).*all asleep from ([0-9.e+-]+) s.*hash ([0-9a-f]+).*/$1 \1 \2 \3/"
}
export -f run
export lab scene T
for ((k = 0; k < n; ++k)); do
  awk -v k="$k" -v n="$n" 'BEGIN { printf "%.7f\n", 1 / 60 + 1e-5 * (2 * k / (n - 1) - 1) }'
done | xargs -P 2 -I{} bash -c 'run "$@"' _ {} "$@" | sort -n |
  awk '{ print; if ($3 < 0) never++; else { gap = $3 - $2; s += gap; m = gap > m ? gap : m; slept++ } }
       END { printf "never asleep: %d of %d", never, NR;
             if (slept > 0) printf "; gap from the last impact to all asleep: mean %.2f s, largest %.2f s", s / slept, m;
             printf "\n" }'
