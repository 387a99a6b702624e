# The bars a rendered street is scored with, read by scripts/evaluate.sh and
# scripts/evaluate-vehicle-models.sh (sourced): cars within 30 m at least a quarter visible
# (--min-visible-fraction 0.25, given by the caller).
# With the semantic image, the goal's bars (docs/evaluation.md "Hard parking streets").
goal=(--bar-class car --bar-range 30 --require-recall 1.0 --max-spurious 0
      --max-median-centre-error 0.4 --max-median-heading-error 8 --min-good-iou-fraction 0.8)
# From the stereo pair alone, the stereo-only path's bars (docs/stereo-only.md): every such car
# found, median centre error <= 0.5 m, median heading error <= 10 degrees.
stereo_only_goal=(--bar-class car --bar-range 30 --require-recall 1.0
                  --max-median-centre-error 0.5 --max-median-heading-error 10)
