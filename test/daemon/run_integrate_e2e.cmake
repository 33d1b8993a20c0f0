# Runs cblox-integrate on 12 frames of the synthetic room (fast and projective) and checks
# the PLY and the accuracy against the analytic room.
file(REMOVE ${OUT})
foreach(integrator fast projective)
  execute_process(
    COMMAND ${INTEGRATE} --config ${CONFIG} --source synthetic-room --frames 12
            --integrator ${integrator} --output ${OUT}
    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${integrator}:\n${out}${err}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "cblox-integrate (${integrator}) exited with ${rc}")
  endif()
  if(NOT EXISTS ${OUT})
    message(FATAL_ERROR "no mesh written to ${OUT}")
  endif()
  file(READ ${OUT} header LIMIT 200)
  if(NOT header MATCHES "^ply\nformat binary_little_endian 1.0\n")
    message(FATAL_ERROR "not a binary PLY: ${header}")
  endif()
  # Vertex RMSE against the analytic room: well under one voxel (20 mm).
  if(NOT out MATCHES "vertex RMSE ([0-9.]+) mm")
    message(FATAL_ERROR "no accuracy line in the output")
  endif()
  if(CMAKE_MATCH_1 GREATER 10.0)
    message(FATAL_ERROR "vertex RMSE ${CMAKE_MATCH_1} mm exceeds 10 mm")
  endif()
endforeach()
