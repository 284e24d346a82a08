# Round 2, the same four-H100 machine right after round 1: three of round 1's synchronizers resumed for 6 more
# minutes and spring_overture fresh for 6.5, all with every matmul in float32 (JAX_DEFAULT_MATMUL_PRECISION=highest).
export DEXGUITAR_PLANS=/tmp/plans JAX_DEFAULT_MATMUL_PRECISION=highest
one() { g=$1; n=$2; s=$3; shift 3; t0=$(date +%s)
  CUDA_VISIBLE_DEVICES=$g dexguitar sync --song /tmp/official/$s.json --out /tmp/runs/gsync/$n \
    --config experiments/sync_songs.py "$@" > /tmp/runs/gsync/$n.r2.log 2>&1
  echo "$n r2 rc=$? seconds=$(( $(date +%s) - t0 )) gpu=$g"; }
one 0 spring_overture spring_overture --resume --max-minutes 6 &
one 1 johnny_b_goodie johnny_b_goodie --resume --max-minutes 6 &
one 2 snow_highest snow --resume --max-minutes 6 &
one 3 spring_highest spring_overture --max-minutes 6.5 &
wait; echo "r2 done"
