#!/usr/bin/env bash
# Here, once: the wheels of .whl/ that training needs, unpacked without MuJoCo's viewers and headers, into
# .data/site.txz (11 MB instead of 34 MB of wheels), so that a carried run and a compilation cache fit the 64 MiB.
set -e
rm -rf /tmp/slim && mkdir /tmp/slim
for w in .whl/mujoco-*.whl .whl/mujoco_mjx-*.whl .whl/trimesh-*.whl .whl/mido-*.whl .whl/pyguitarpro-*.whl; do
  unzip -q -o "$w" -d /tmp/slim; done
rm -rf /tmp/slim/mujoco/experimental /tmp/slim/mujoco/_render_filament* /tmp/slim/mujoco/include /tmp/slim/mujoco/_simulate*
mkdir -p .data && tar cJf .data/site.txz -C /tmp slim && ls -la .data/site.txz
