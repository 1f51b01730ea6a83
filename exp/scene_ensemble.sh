#!/bin/bash
# How a scene ends, over an ensemble of time steps.
#
# Piles and stacks are chaotic: one run of a change against one run of the base says little
# (the large scene's late restlessness ranged from 0 to 23 steps between time steps a few 10⁻⁶ s
# apart on the same code). This runs `contact_lab scene` at N time steps spread over
# 1/60 ± 10⁻⁵ s, as many at a time as there are cores.
#   Default: how restless the scene is at the end (sleep off, 30 s). Per run: the fastest particle
#   in the last 5 s (m/s), the mean fastest particle in the last 10 s (m/s) and the steps of the
#   last 10 s with a particle at 1 cm/s or more; then the mean of those steps and how many runs
#   had any.
#   --sleep: how soon it falls asleep after its last impact (sleep on, 15 s). Per run: the last
#   particle impact (s), when every body was asleep (s; −1: not by the end) and the state hash;
#   then how many runs never slept, and the mean and largest gap from the last impact to all
#   asleep over the others (issue 11's target: ≤ 1 s).
# Options after N go to contact_lab and override these (e.g. T=12, sub=8, threads=1).
#
# usage: exp/scene_ensemble.sh [--sleep] CONTACT_LAB SCENE.json [N=8] [contact_lab options...]
#   e.g. exp/scene_ensemble.sh build/release/exp/contact_lab assets/scenes/large.json 16 nodamp=1
#        exp/scene_ensemble.sh --sleep build/release/exp/contact_lab assets/scenes/pile.json 8
set -euo pipefail
mode=restless
if [ "${1:-}" = --sleep ]; then
  mode=sleep
  shift
fi
if [ $# -lt 2 ]; then
  sed -n '2,21p' "$0" | sed 's/^# \{0,1\}//'
  exit 2
fi
lab=$1
scene=$2
n=${3:-8}
shift $(($# < 3 ? $# : 3))
[ -x "$lab" ] || { echo "scene_ensemble: $lab: not an executable contact_lab" >&2; exit 2; }
[ -r "$scene" ] || { echo "scene_ensemble: $scene: cannot read the scene" >&2; exit 2; }
case $n in '' | *[!0-9]* | 0 | 1) echo "scene_ensemble: N must be an integer ≥ 2, got '$n'" >&2; exit 2 ;; esac

restless() {  # time step → dt, fastest in the last 5 s, mean fastest in the last 10 s, steps
  "$lab" scene path="$scene" sleep=0 T=30 dt="$1" every=1000000 "${@:2}" | tail -n 1 |
    sed -E "s/.*last 5 s ([0-9.e+-]+) m.s.*last 10 s: mean fastest ([0-9.e+-]+) m.s, ([0-9]+) steps.*/$1 \1 \2 \3/"
}
sleep_gap() {  # time step → dt, last particle impact, all asleep from, state hash
  "$lab" scene path="$scene" sleep=1 T=15 dt="$1" every=1000000 "${@:2}" | tail -n 1 |
    sed -E "s/.*a particle's: ([0-9.e+-]+) s\).*all asleep from ([0-9.e+-]+) s.*hash ([0-9a-f]+).*/$1 \1 \2 \3/"
}
export -f restless sleep_gap
export lab scene
if [ $mode = sleep ]; then
  run=sleep_gap
  summary='{ print; if ($3 < 0) never++; else { gap = $3 - $2; s += gap; m = gap > m ? gap : m; slept++ } }
    END { printf "never asleep: %d of %d", never, NR;
          if (slept > 0) printf "; gap from the last impact to all asleep: mean %.2f s, largest %.2f s", s / slept, m;
          printf "\n" }'
else
  run=restless
  summary='{ print; steps += $4; if ($4 > 0) any++ }
    END { printf "mean steps >= 1 cm/s in the last 10 s: %.2f; runs with any: %d of %d\n", steps / NR, any, NR }'
fi
for ((k = 0; k < n; ++k)); do
  awk -v k="$k" -v n="$n" 'BEGIN { printf "%.7f\n", 1 / 60 + 1e-5 * (2 * k / (n - 1) - 1) }'
done | xargs -P "$(nproc)" -I{} bash -c "$run"' "$@"' _ {} "$@" | sort -n | awk "$summary"
