# The cluster path on a real single-node Slurm (label `slurm`): scripts/slurm/local-cluster.sh
# starts munged, slurmctld and slurmd, tests/cli/slurm_array.sh runs a 3-task array with one
# task killed and resubmitted, the merge jobs, and compares with a one-process batch. Reported
# as skipped (exit 77) where slurm-wlm or munge is not installed.
add_test(NAME cli.slurm_array
    COMMAND ${PROJECT_SOURCE_DIR}/scripts/slurm/local-cluster.sh --timeout 150 --
        ${CMAKE_CURRENT_SOURCE_DIR}/slurm_array.sh $<TARGET_FILE:cloud-analysis>
        ${PROJECT_SOURCE_DIR}/samples ${PROJECT_SOURCE_DIR}/scripts/slurm
        ${CMAKE_CURRENT_BINARY_DIR}/slurm_array)
set_tests_properties(cli.slurm_array PROPERTIES LABELS slurm SKIP_RETURN_CODE 77 TIMEOUT 180)
