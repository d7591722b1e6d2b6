# Small helpers shared by the CMake files of omnislam.

# omnislam_add_gtest(NAME SOURCES... LIBS ... [LABELS ...] [TIMEOUT s])
# One GoogleTest executable per test source file, registered with CTest test by test.
function(omnislam_add_gtest name)
  cmake_parse_arguments(T "WHOLE" "TIMEOUT" "SOURCES;LIBS;LABELS" ${ARGN})
  set(main GTest::gtest_main)
  if(T_WHOLE)
    set(main omnislam_gtest_main_whole)  # tests/CMakeLists.txt: skips reported to CTest as 77
  endif()
  add_executable(${name} ${T_SOURCES})
  if("unit" IN_LIST T_LABELS)  # the target unit_tests (tests/CMakeLists.txt) builds only these
    set_property(GLOBAL APPEND PROPERTY OMNISLAM_UNIT_TEST_TARGETS ${name})
  endif()
  target_link_libraries(${name} PRIVATE ${T_LIBS} GTest::gtest ${main})
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests/support)
  target_compile_definitions(${name} PRIVATE
    OMNISLAM_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    OMNISLAM_BIN_DIR="${CMAKE_RUNTIME_OUTPUT_DIRECTORY}"
    OMNISLAM_BUILD_DIR="${CMAKE_BINARY_DIR}")
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT 120)
  endif()
  math(EXPR T_TIMEOUT "${T_TIMEOUT} * ${OMNISLAM_TIMEOUT_FACTOR}")
  if(T_WHOLE)
    # One CTest entry for the whole executable: its suite-level set-up (e.g. launching the
    # processes once) is shared by all of its tests.
    # Its main (tests/support/gtest_main_whole.cpp) exits with 77 when every test it ran skipped.
    add_test(NAME ${name} COMMAND ${name})
    set_tests_properties(${name} PROPERTIES TIMEOUT ${T_TIMEOUT} LABELS "${T_LABELS}" SKIP_RETURN_CODE 77)
  else()
    gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60
      PROPERTIES TIMEOUT ${T_TIMEOUT} LABELS "${T_LABELS}")
  endif()
endfunction()

# Every test source file in DIR becomes its own test executable linked with LIBS.
function(omnislam_add_gtests_in_dir dir)
  cmake_parse_arguments(T "WHOLE" "TIMEOUT;PREFIX" "LIBS;LABELS" ${ARGN})
  set(whole "")
  if(T_WHOLE)
    set(whole WHOLE)
  endif()
  file(GLOB srcs CONFIGURE_DEPENDS ${dir}/test_*.cpp)
  foreach(src ${srcs})
    get_filename_component(stem ${src} NAME_WE)
    omnislam_add_gtest(${T_PREFIX}${stem} SOURCES ${src} LIBS ${T_LIBS} LABELS ${T_LABELS} TIMEOUT ${T_TIMEOUT} ${whole})
  endforeach()
endfunction()
