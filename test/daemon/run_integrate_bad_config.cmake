# A bad configuration must fail with exit status 2 and a message naming the key.
file(WRITE ${WORK}/bad.yaml "integrator:\n  num_threads: 0\n")
execute_process(COMMAND ${INTEGRATE} --config ${WORK}/bad.yaml --frames 1 --output ${WORK}/x.ply
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 2 OR NOT err MATCHES "integrator.num_threads")
  message(FATAL_ERROR "expected exit 2 naming integrator.num_threads, got ${rc}: ${err}")
endif()
file(WRITE ${WORK}/bad2.yaml "layer:\n  voxel_sise: 0.02\n")
execute_process(COMMAND ${INTEGRATE} --config ${WORK}/bad2.yaml --frames 1 --output ${WORK}/x.ply
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 2 OR NOT err MATCHES "layer.voxel_sise: unknown setting")
  message(FATAL_ERROR "expected exit 2 naming layer.voxel_sise, got ${rc}: ${err}")
endif()
execute_process(COMMAND ${INTEGRATE} --source nowhere --frames 1 --output ${WORK}/x.ply
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 2 OR NOT err MATCHES "--source")
  message(FATAL_ERROR "expected exit 2 for an unknown source, got ${rc}: ${err}")
endif()
