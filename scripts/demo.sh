#!/usr/bin/env bash
# Installs what is missing, builds (Release), runs cloud-analysis on the bundled samples and
# scene-render on its output and on the crafted baseline, then prints where each output is.
# usage: scripts/demo.sh [OUTPUT_DIR]      (default: out/demo)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

out=${1:-"$STEREOSCENE_ROOT/out/demo"}
build="$STEREOSCENE_ROOT/build"
stereoscene_build "$build" Release -- cloud-analysis scene-render

analyse="$build/cloud_analysis/cloud-analysis"
render="$build/scene_viewer/scene-render"
samples="$STEREOSCENE_ROOT/samples"
mkdir -p "$out"
outputs=()
note() { outputs+=("$(printf '%-34s %s' "$1" "$2")"); }

# 1. cloud-analysis on the bundled synthetic street: clouds, disparity, entities.
s="$samples/synthetic"
inputs=(--left "$s/left.png" --right "$s/right.png" --semantic "$s/semantic.png"
        --calib "$s/calib.yaml" --frame synthetic-street)
echo "== cloud-analysis: synthetic street (instances)" >&2
"$analyse" "${inputs[@]}" -o "$out/synthetic-instances.json" \
    --xyz "$out/synthetic.xyz" --pcd "$out/synthetic.pcd" --ply "$out/synthetic.ply" \
    --disparity-png "$out/synthetic-disparity.png" --timings
note "entities (instances)" "$out/synthetic-instances.json"
note "cloud for CloudCompare" "$out/synthetic.xyz"
note "cloud for PCL" "$out/synthetic.pcd"
note "cloud for MeshLab/CloudCompare" "$out/synthetic.ply"
note "disparity (8-bit)" "$out/synthetic-disparity.png"
for method in centroid variance; do
    echo "== cloud-analysis: synthetic street (thesis extractor: $method)" >&2
    "$analyse" "${inputs[@]}" --method "$method" -o "$out/synthetic-$method.json"
    note "entities ($method, thesis)" "$out/synthetic-$method.json"
done

# 2. scene-render: the crafted baseline and the analysis in camera, chase and BEV views.
for view in camera chase bev; do
    "$render" "$samples/baselines/street.json" --view "$view" -o "$out/baseline-$view.png"
    note "baseline, $view view" "$out/baseline-$view.png"
    "$render" "$out/synthetic-instances.json" --view "$view" -o "$out/synthetic-$view.png"
    note "synthetic analysis, $view view" "$out/synthetic-$view.png"
done
"$render" "$out/synthetic-instances.json" --view camera --background "$s/left.png" \
    -o "$out/synthetic-camera-over-left.png"
note "analysis over the left image" "$out/synthetic-camera-over-left.png"
"$render" "$out/synthetic-instances.json" --view chase --cloud "$out/synthetic.ply" \
    -o "$out/synthetic-chase-cloud.png"
note "analysis + point cloud, chase" "$out/synthetic-chase-cloud.png"
"$render" grid --inputs "$s/truth.json" "$out/synthetic-centroid.json" \
    "$out/synthetic-variance.json" "$out/synthetic-instances.json" \
    --labels "truth" "centre of mass" "variance" "instances" --view bev \
    -o "$out/synthetic-comparison.png"
note "comparison grid (BEV)" "$out/synthetic-comparison.png"
"$render" "$samples/baselines/street.json" --view chase --export-glb "$out/baseline.glb" \
    -o "$out/baseline-chase.png"
note "baseline scene as glTF" "$out/baseline.glb"

# 3. A real KITTI frame, when the shared data is beside the project (never bundled).
kitti="$STEREOSCENE_ROOT/../shared/data/kitti15"
if [ -d "$kitti/image_2" ]; then
    echo "== cloud-analysis: KITTI 2015 frame 000000_10 (from ../shared/data)" >&2
    "$analyse" --kitti-root "$kitti" --frame 000000_10 -o "$out/kitti-000000_10.json" \
        --ply "$out/kitti-000000_10.ply" --timings
    "$render" "$out/kitti-000000_10.json" --view camera \
        --background "$kitti/image_2/000000_10.png" -o "$out/kitti-000000_10-camera.png"
    "$render" "$out/kitti-000000_10.json" --view bev -o "$out/kitti-000000_10-bev.png"
    note "KITTI entities" "$out/kitti-000000_10.json"
    note "KITTI camera view over the image" "$out/kitti-000000_10-camera.png"
    note "KITTI BEV" "$out/kitti-000000_10-bev.png"
fi

echo
echo "Demo outputs:"
printf '  %s\n' "${outputs[@]}"
