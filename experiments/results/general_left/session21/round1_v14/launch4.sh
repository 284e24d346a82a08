# Four GPUs, GSync with the hold reward on planner v14 (one-thread plans carried): bumblebee x2 seeds, spring, prelude.
mkdir -p /tmp/plans /tmp/official /tmp/runs/gsync && cp $REPO/.data/plans/*.npz /tmp/plans/ \
  && cp $REPO/.data/official/*.json /tmp/official/
export DEXGUITAR_PLANS=/tmp/plans
one() { g=$1; n=$2; s=$3; c=$4; shift 4; t0=$(date +%s)
  CUDA_VISIBLE_DEVICES=$g dexguitar sync --song /tmp/official/$s.json --out /tmp/runs/gsync/$n \
    --config $c --max-minutes ${MIN:-8} "$@" > /tmp/runs/gsync/$n.log 2>&1
  echo "$n rc=$? seconds=$(( $(date +%s) - t0 )) gpu=$g"; }
one 0 bumblebee_s1 flight_of_the_bumblebee1 experiments/sync_hold.py --seed 1 &
one 1 bumblebee_s2 flight_of_the_bumblebee1 experiments/sync_hold.py --seed 2 &
one 2 spring_s1 spring_overture experiments/sync_hold.py --seed 1 &
one 3 prelude_s3 prelude1_in_c_major_chords experiments/sync_hold.py --seed 3 &
wait
echo "gsync done"
