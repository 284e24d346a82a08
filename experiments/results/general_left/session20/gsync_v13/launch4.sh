# Four GPUs, GSync with the hold reward on planner v13 (plans carried): snow, dont_cry, prelude, capriccio.
mkdir -p /tmp/plans /tmp/official /tmp/runs/gsync && cp $REPO/.data/plans/*.npz /tmp/plans/ \
  && cp $REPO/.data/official/*.json /tmp/official/
export DEXGUITAR_PLANS=/tmp/plans
one() { g=$1; n=$2; s=$3; c=$4; shift 4; t0=$(date +%s)
  CUDA_VISIBLE_DEVICES=$g dexguitar sync --song /tmp/official/$s.json --out /tmp/runs/gsync/$n \
    --config $c --max-minutes ${MIN:-8} "$@" > /tmp/runs/gsync/$n.log 2>&1
  echo "$n rc=$? seconds=$(( $(date +%s) - t0 )) gpu=$g"; }
one 0 snow snow experiments/sync_hold.py &
one 1 dont_cry dont_cry experiments/sync_hold.py &
one 2 prelude1_in_c_major_chords prelude1_in_c_major_chords experiments/sync_hold.py &
one 3 capriccio_op59_no16 capriccio_op59_no16 experiments/sync_hold.py &
wait
echo "gsync done"
