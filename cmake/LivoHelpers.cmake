# Helpers shared by every target of the suite.

# Warnings per target (never global), no -ffast-math; -march=native only on request.
function(livo_target_defaults target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wno-unused-parameter)
  if(LIVO_NATIVE)
    target_compile_options(${target} PRIVATE -march=native)
  endif()
endfunction()

# Adds every immediate sub-folder of DIR that holds a CMakeLists.txt, in sorted order.
function(livo_add_subdirectories dir)
  file(GLOB children RELATIVE ${CMAKE_CURRENT_SOURCE_DIR}/${dir} ${CMAKE_CURRENT_SOURCE_DIR}/${dir}/*)
  list(SORT children)
  foreach(child ${children})
    if(EXISTS ${CMAKE_CURRENT_SOURCE_DIR}/${dir}/${child}/CMakeLists.txt)
      add_subdirectory(${dir}/${child})
    endif()
  endforeach()
endfunction()

# livo_library(NAME <n> DEPS <targets...>): libs/<n>/src/*.cpp + include/, target livo_<n>, alias livo::<n>.
function(livo_library)
  cmake_parse_arguments(ARG "" "NAME" "DEPS;PRIVATE_DEPS" ${ARGN})
  file(GLOB srcs CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/src/*.cpp)
  add_library(livo_${ARG_NAME} STATIC ${srcs})
  add_library(livo::${ARG_NAME} ALIAS livo_${ARG_NAME})
  target_include_directories(livo_${ARG_NAME} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
  target_link_libraries(livo_${ARG_NAME} PUBLIC ${ARG_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  livo_target_defaults(livo_${ARG_NAME})
  set_property(GLOBAL APPEND PROPERTY LIVO_LIBRARIES livo_${ARG_NAME})
endfunction()

# livo_executable(NAME <binary> DEPS <targets...>): processes/<x>/*.cpp into build/bin/<binary>.
function(livo_executable)
  cmake_parse_arguments(ARG "" "NAME" "DEPS" ${ARGN})
  file(GLOB srcs CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.cpp)
  add_executable(${ARG_NAME} ${srcs})
  target_link_libraries(${ARG_NAME} PRIVATE ${ARG_DEPS})
  livo_target_defaults(${ARG_NAME})
endfunction()
