# Run on round 2's warm machine after its gsync run: two of its runs resumed for 4.5 more minutes each.
export DEXGUITAR_PLANS=/tmp/plans
r() { g=$1; n=$2; s=$3; t0=$(date +%s); CUDA_VISIBLE_DEVICES=$g dexguitar sync --song /tmp/official/$s.json --config experiments/sync_hold.py --seed 1 --resume --out /tmp/runs/gsync/$n --max-minutes 4.5 > /tmp/runs/gsync/$n.resume.log 2>&1; echo "$n rc=$? seconds=$(( $(date +%s) - t0 ))"; }
r 0 bumblebee15_s1 flight_of_the_bumblebee1 & r 1 spring15_s1 spring_overture & wait
