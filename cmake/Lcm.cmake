# LCM 1.3.1 ships no CMake package (see ../shared/docs/lcm-notes.md): find it by hand.
find_path(LCM_INCLUDE_DIR lcm/lcm-cpp.hpp REQUIRED)
find_library(LCM_LIBRARY lcm REQUIRED)
find_program(LCM_GEN lcm-gen REQUIRED)
find_file(LCM_JAR lcm.jar PATHS /usr/share/java /usr/local/share/java)
add_library(lcm::lcm INTERFACE IMPORTED)
set_target_properties(lcm::lcm PROPERTIES
  INTERFACE_INCLUDE_DIRECTORIES "${LCM_INCLUDE_DIR}"
  INTERFACE_LINK_LIBRARIES "${LCM_LIBRARY}")
