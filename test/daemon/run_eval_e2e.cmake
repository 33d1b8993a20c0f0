# Runs cblox-eval end to end on files this script writes (WORK is a scratch folder):
#  - a ground-truth plane [0, 2] x [0, 1] (ASCII PLY, 2 triangles) and a reconstruction of it
#    5 mm above (ASCII PLY, a 21 x 11 vertex grid), so every vertex error is 5 mm;
#  - a ground-truth trajectory (TUM) and an estimate shifted by (1, 2, 0) m, which the SE(3)
#    alignment removes (ATE 0). The alignment is then also applied to the reconstruction,
#    so that one is written in the shifted frame too.
# Checks exit status 0, the summary, the JSON keys and values, the PNGs, and that bad
# arguments and missing files exit with status 2 and a message naming the problem.
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

# Ground truth: two triangles, counter-clockwise seen from +z.
file(WRITE ${WORK}/gt.ply "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n"
  "property float y\nproperty float z\nelement face 2\nproperty list uchar int vertex_indices\n"
  "end_header\n0 0 0\n2 0 0\n2 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n")

# Reconstruction: a grid 5 mm above the plane, in the estimate's frame (shifted by (1, 2, 0)).
set(vertices "")
foreach(j RANGE 0 10)
  foreach(i RANGE 0 20)
    math(EXPR x_tenths "${i} + 10")  # x = i / 10 + 1
    math(EXPR y_tenths "${j} + 20")  # y = j / 10 + 2
    string(APPEND vertices "${x_tenths}e-1 ${y_tenths}e-1 0.005\n")
  endforeach()
endforeach()
set(faces "")
foreach(j RANGE 0 9)
  foreach(i RANGE 0 19)
    math(EXPR a "${j} * 21 + ${i}")
    math(EXPR b "${a} + 1")
    math(EXPR c "${a} + 22")
    math(EXPR d "${a} + 21")
    string(APPEND faces "3 ${a} ${b} ${c}\n3 ${a} ${c} ${d}\n")
  endforeach()
endforeach()
file(WRITE ${WORK}/recon.ply "ply\nformat ascii 1.0\nelement vertex 231\nproperty float x\n"
  "property float y\nproperty float z\nelement face 400\n"
  "property list uchar int vertex_indices\nend_header\n${vertices}${faces}")

# Trajectories: 40 poses at 10 Hz on a zig-zag path (not collinear, so SE(3) alignment is
# determined); the estimate is the same path shifted by (1, 2, 0) m.
set(gt_lines "# timestamp tx ty tz qx qy qz qw\n")
set(est_lines "")
foreach(k RANGE 0 39)
  math(EXPR t_tenths "${k} + 10000")
  math(EXPR x_cm "${k} * 5")
  math(EXPR y_cm "(${k} % 4) * 10")
  math(EXPR z_cm "100 + (${k} % 3) * 5")
  math(EXPR xe_cm "${x_cm} + 100")
  math(EXPR ye_cm "${y_cm} + 200")
  string(APPEND gt_lines "${t_tenths}e-1 ${x_cm}e-2 ${y_cm}e-2 ${z_cm}e-2 0 0 0 1\n")
  string(APPEND est_lines "${t_tenths}e-1 ${xe_cm}e-2 ${ye_cm}e-2 ${z_cm}e-2 0 0 0 1\n")
endforeach()
file(WRITE ${WORK}/gt.txt "${gt_lines}")
file(WRITE ${WORK}/est.txt "${est_lines}")

execute_process(
  COMMAND ${EVAL} --gt-mesh ${WORK}/gt.ply --mesh ${WORK}/recon.ply
          --gt-trajectory ${WORK}/gt.txt --trajectory ${WORK}/est.txt --align se3
          --threshold 0.01 --sample-spacing 0.02 --voxel-size 0.1 --block-voxels 2
          --map-blocks 123 --map-bytes 45678
          --json ${WORK}/eval.json --error-png ${WORK}/error.png
          --trajectory-png ${WORK}/trajectory.png
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message(STATUS "cblox-eval:\n${out}${err}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cblox-eval exited with ${rc}")
endif()
if(NOT out MATCHES "accuracy: RMSE 5\\.00 mm")
  message(FATAL_ERROR "no 5.00 mm accuracy line in the output")
endif()
foreach(png error.png trajectory.png)
  if(NOT EXISTS ${WORK}/${png})
    message(FATAL_ERROR "${png} was not written")
  endif()
  file(READ ${WORK}/${png} signature LIMIT 8 HEX)
  if(NOT signature STREQUAL "89504e470d0a1a0a")
    message(FATAL_ERROR "${png} is not a PNG (${signature})")
  endif()
endforeach()

file(READ ${WORK}/eval.json json)
# Every section and key is present; numbers read back (if(LESS) compares as doubles).
string(JSON rmse GET "${json}" mesh accuracy rmse_m)
string(JSON median GET "${json}" mesh accuracy median_m)
string(JSON p90 GET "${json}" mesh accuracy p90_m)
string(JSON vertices GET "${json}" mesh accuracy vertices)
string(JSON completeness GET "${json}" mesh completeness completeness)
string(JSON reference GET "${json}" mesh completeness reference)
string(JSON mesh_aligned GET "${json}" inputs mesh_aligned)
string(JSON applied GET "${json}" mesh alignment applied)
string(JSON ate GET "${json}" trajectory ate rmse_m)
string(JSON matched GET "${json}" trajectory matched_poses)
string(JSON rpe_pairs GET "${json}" trajectory rpe pairs)
string(JSON surface_blocks GET "${json}" map surface_blocks blocks)
string(JSON voxel_bytes GET "${json}" map surface_blocks voxel_bytes)
string(JSON reported_blocks GET "${json}" map reported_blocks)
string(JSON reported_bytes GET "${json}" map reported_bytes)
string(JSON gt_mesh GET "${json}" inputs gt_mesh)
message(STATUS "rmse ${rmse}, median ${median}, p90 ${p90}, completeness ${completeness}, "
               "ATE ${ate}, surface blocks ${surface_blocks}")

# Vertex errors are 5 mm (float vertices: within 1e-6 m).
foreach(name rmse median p90)
  if(${name} LESS 0.004999 OR ${name} GREATER 0.005001)
    message(FATAL_ERROR "mesh ${name} ${${name}} is not 0.005")
  endif()
endforeach()
if(NOT vertices EQUAL 231)
  message(FATAL_ERROR "mesh accuracy over ${vertices} vertices, expected 231")
endif()
if(NOT completeness EQUAL 1 OR NOT reference STREQUAL "triangles")
  message(FATAL_ERROR "completeness ${completeness} (${reference}), expected 1 (triangles)")
endif()
if(NOT mesh_aligned STREQUAL "ON" OR NOT applied STREQUAL "ON")
  message(FATAL_ERROR "the trajectory's alignment was not applied to the mesh")
endif()
if(ate GREATER 1e-6)
  message(FATAL_ERROR "ATE ${ate} m after SE(3) alignment, expected 0")
endif()
if(NOT matched EQUAL 40 OR NOT rpe_pairs EQUAL 39)
  message(FATAL_ERROR "matched ${matched} poses and ${rpe_pairs} RPE pairs, expected 40 and 39")
endif()
# The plane [1, 3] x [2, 3] at z = 0.005 in the estimate's frame, 0.2 m blocks: x blocks 5..15
# (x = 3.0 is the first point of block 15), y blocks 10..15, z block 0: 11 * 6 = 66 blocks.
if(NOT surface_blocks EQUAL 66 OR NOT voxel_bytes EQUAL 6336)
  message(FATAL_ERROR "surface blocks ${surface_blocks} (${voxel_bytes} bytes), expected 66 "
                      "(6336 bytes)")
endif()
if(NOT reported_blocks EQUAL 123 OR NOT reported_bytes EQUAL 45678)
  message(FATAL_ERROR "reported map size ${reported_blocks} / ${reported_bytes} not passed through")
endif()
if(NOT gt_mesh STREQUAL "${WORK}/gt.ply")
  message(FATAL_ERROR "inputs.gt_mesh is '${gt_mesh}'")
endif()

# Only the mesh part, without alignment: the JSON's trajectory section is null.
execute_process(
  COMMAND ${EVAL} --gt-mesh ${WORK}/gt.ply --mesh ${WORK}/gt.ply --json ${WORK}/self.json
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "self evaluation exited with ${rc}: ${err}")
endif()
file(READ ${WORK}/self.json json)
string(JSON trajectory_type TYPE "${json}" trajectory)
string(JSON self_rmse GET "${json}" mesh accuracy rmse_m)
if(NOT trajectory_type STREQUAL "NULL" OR NOT self_rmse EQUAL 0)
  message(FATAL_ERROR "self evaluation: trajectory ${trajectory_type}, rmse ${self_rmse}")
endif()

# A mesh without ground truth, coloured by height: here a plane 5 mm up, seen with y up
# (so the heights run along y, 0 .. 1 m).
execute_process(COMMAND ${EVAL} --mesh ${WORK}/recon.ply --height-png ${WORK}/height.png --up y
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT out MATCHES "wrote ${WORK}/height.png")
  message(FATAL_ERROR "height picture: expected exit 0 and the file, got ${rc}: ${out}${err}")
endif()
file(READ ${WORK}/height.png signature LIMIT 8 HEX)
if(NOT signature STREQUAL "89504e470d0a1a0a")
  message(FATAL_ERROR "height.png is not a PNG (${signature})")
endif()

# Usage errors exit with status 2 and say what is wrong.
function(expect_usage_error what pattern)
  execute_process(COMMAND ${EVAL} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out
                  ERROR_VARIABLE err)
  if(NOT rc EQUAL 2 OR NOT err MATCHES "${pattern}")
    message(FATAL_ERROR "${what}: expected exit 2 and '${pattern}', got ${rc}: ${err}")
  endif()
endfunction()
expect_usage_error("unknown flag" "not expected: --bogus" --bogus)
expect_usage_error("nothing to do" "nothing to evaluate")
expect_usage_error("missing file" "${WORK}/missing.ply: no such file"
                   --gt-mesh ${WORK}/missing.ply --mesh ${WORK}/recon.ply)
expect_usage_error("unpaired mesh" "--mesh needs --gt-mesh" --mesh ${WORK}/recon.ply)
expect_usage_error("height without mesh" "--height-png needs --mesh" --height-png ${WORK}/h.png)
expect_usage_error("bad up axis" "--up: must be x, y, z, -x, -y or -z"
                   --mesh ${WORK}/recon.ply --height-png ${WORK}/h.png --up w)
expect_usage_error("bad number" "--threshold: needs a finite number"
                   --gt-mesh ${WORK}/gt.ply --mesh ${WORK}/recon.ply --threshold abc)
expect_usage_error("bad alignment" "--align: must be none, se3 or sim3"
                   --gt-trajectory ${WORK}/gt.txt --trajectory ${WORK}/est.txt --align affine)
file(WRITE ${WORK}/broken.ply "ply\nformat ascii 1.0\nelement vertex 1\nend_header\n")
expect_usage_error("malformed mesh" "broken.ply"
                   --gt-mesh ${WORK}/gt.ply --mesh ${WORK}/broken.ply)
file(WRITE ${WORK}/mesh.stl "solid x\n")
expect_usage_error("unknown format" "unsupported reconstruction format '.stl'"
                   --gt-mesh ${WORK}/gt.ply --mesh ${WORK}/mesh.stl)

# An evaluation failure (no pose matches in time) exits with status 1.
file(WRITE ${WORK}/late.txt "5000 0 0 0 0 0 0 1\n5001 1 0 0 0 0 0 1\n5002 1 1 0 0 0 0 1\n")
execute_process(COMMAND ${EVAL} --gt-trajectory ${WORK}/gt.txt --trajectory ${WORK}/late.txt
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 1 OR NOT err MATCHES "no estimated pose matches")
  message(FATAL_ERROR "unmatched trajectories: expected exit 1, got ${rc}: ${err}")
endif()
