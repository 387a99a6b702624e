# Seeds of the streets scripts/make-parking-scene.py renders for evaluation, read by
# scripts/evaluate.sh, evaluate-instances.sh and evaluate-vehicle-models.sh (sourced) and
# scripts/train-segment-classifier.py (parsed: NAME="..." lines).
# Parking, kerbside and pedestrian streets are tuning data; the held-out seeds give a parking, a
# kerbside and a pedestrian street each and are never used to choose a parameter.
parking_seeds="2 4 5 6 7 8 9 10 11 12 23 24 25 26 27 28 29 30 31 32"
kerbside_seeds="2 3 4 5 6 7 8 9 23 24 25 26 27 28 29 30 31 32"
pedestrian_seeds="2 3 4 5 6 7 8 9"
held_out_seeds="13 14 15 16 17 18 19 20 21 22"

# The make-parking-scene.py flags of a kind of street (parking, kerbside or pedestrians), into
# the array street_flags.
set_street_flags() {
    case "$1" in
        parking) street_flags=() ;;
        kerbside) street_flags=(--kerbside) ;;
        pedestrians) street_flags=(--kerbside --pedestrians) ;;
        *) echo "street-seeds.sh: unknown kind of street: $1" >&2; return 1 ;;
    esac
}
