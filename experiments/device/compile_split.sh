#!/bin/bash
# On the device (carry .data with site.txz and the official tabs in .data/official; models/policies holding only
# left_general and right_mixed): experiments/compile_split.py three times, one process each, one compilation cache.
set -e
tar xJf .data/site.txz -C /tmp && rm -rf /tmp/site && mv /tmp/slim /tmp/site
export PYTHONPATH=/tmp/site:$PWD PYTHONUNBUFFERED=1 DEXGUITAR_CACHE=/tmp/xla DEXGUITAR_PLANS=/tmp/plans
nvidia-smi --query-gpu=name --format=csv,noheader | tee $OUT/gpu.txt
for run in 1 2 3; do
  python3 experiments/compile_split.py .data/official/spring_overture.json 2>> $OUT/log.txt | tail -1 | tee -a $OUT/split.jsonl
done
ls -la /tmp/xla | tee -a $OUT/log.txt
