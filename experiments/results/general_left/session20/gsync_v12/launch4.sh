# Four GPUs, GSync with the hold reward on planner v12 (plans carried): snow, sonata, bumblebee (hold 1), spring (hold 3).
mkdir -p /tmp/plans /tmp/official /tmp/runs/gsync && cp $REPO/.data/plans/*.npz /tmp/plans/ \
  && cp $REPO/.data/official/*.json /tmp/official/ && cp $REPO/.data/sync_hold3.py /tmp/sync_hold3.py
export DEXGUITAR_PLANS=/tmp/plans
one() { g=$1; n=$2; s=$3; c=$4; shift 4; t0=$(date +%s)
  CUDA_VISIBLE_DEVICES=$g dexguitar sync --song /tmp/official/$s.json --out /tmp/runs/gsync/$n \
    --config $c --max-minutes ${MIN:-8} "$@" > /tmp/runs/gsync/$n.log 2>&1
  echo "$n rc=$? seconds=$(( $(date +%s) - t0 )) gpu=$g"; }
one 0 snow snow experiments/sync_hold.py &
one 1 spring_overture_h3 spring_overture /tmp/sync_hold3.py &
one 2 sonata sonata_in_f_major_ms84_no14 experiments/sync_hold.py &
one 3 bumblebee flight_of_the_bumblebee1 experiments/sync_hold.py &
wait
echo "gsync done"
