# cblox_add_test(NAME name SOURCES a.cc b.cc LIBS lib1 lib2 [LABELS l1 l2])
# Builds a GoogleTest executable and registers each of its tests with CTest.
include(GoogleTest)
function(cblox_add_test)
  cmake_parse_arguments(ARG "" "NAME" "SOURCES;LIBS;LABELS" ${ARGN})
  add_executable(${ARG_NAME} ${ARG_SOURCES})
  target_link_libraries(${ARG_NAME} PRIVATE ${ARG_LIBS} GTest::gtest GTest::gtest_main cblox_warnings)
  target_compile_definitions(${ARG_NAME} PRIVATE
    CBLOX_SHARED_DATA_DIR="${CMAKE_SOURCE_DIR}/../shared/data")
  gtest_discover_tests(${ARG_NAME} TEST_PREFIX "${ARG_NAME}." DISCOVERY_TIMEOUT 60
    PROPERTIES LABELS "${ARG_LABELS}")
endfunction()
