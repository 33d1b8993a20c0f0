# A bad configuration or source must fail with exit status 2 and a message naming it.
function(expect_usage_error what pattern)
  execute_process(COMMAND ${INTEGRATE} ${ARGN} --frames 1 --output ${WORK}/x.ply
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 2 OR NOT err MATCHES "${pattern}")
    message(FATAL_ERROR "${what}: expected exit 2 and '${pattern}', got ${rc}: ${err}")
  endif()
endfunction()

file(WRITE ${WORK}/bad.yaml "integrator:\n  num_threads: 0\n")
expect_usage_error("invalid value" "integrator.num_threads" --config ${WORK}/bad.yaml)
file(WRITE ${WORK}/bad2.yaml "layer:\n  voxel_sise: 0.02\n")
expect_usage_error("misspelt key" "layer.voxel_sise: unknown setting" --config ${WORK}/bad2.yaml)
expect_usage_error("unknown source" "source 'nowhere' has no kind" --source nowhere)
expect_usage_error("unknown noise preset" "noise preset" --noise loud)
expect_usage_error("unknown trajectory" "unknown trajectory 'spiral'" --source sim:room --trajectory spiral)
