# Debian's liblcm-dev 1.3.1 ships no CMake helpers, so lcm-gen is driven here directly.
# kincal_lcm_types(<target> <file.lcm>...) generates C++ headers and the Python package
# into the build tree and defines the INTERFACE target kincal::lcmtypes.
find_program(LCM_GEN lcm-gen REQUIRED)

function(kincal_lcm_types target)
  set(cpp_dir ${CMAKE_BINARY_DIR}/lcmgen/cpp)
  set(py_dir ${CMAKE_BINARY_DIR}/lcmgen/python)
  set(outputs)
  set(sources)
  set(py_outputs ${py_dir}/kincal/__init__.py)
  foreach(lcm_file ${ARGN})
    get_filename_component(type_name ${lcm_file} NAME_WE)
    set(src ${CMAKE_CURRENT_SOURCE_DIR}/${lcm_file})
    list(APPEND sources ${src})
    set(hpp ${cpp_dir}/kincal/${type_name}.hpp)
    add_custom_command(
      OUTPUT ${hpp}
      COMMAND ${CMAKE_COMMAND} -E make_directory ${cpp_dir}
      COMMAND ${LCM_GEN} --cpp --cpp-hpath ${cpp_dir} ${src}
      DEPENDS ${src}
      COMMENT "lcm-gen ${type_name}"
      VERBATIM)
    list(APPEND outputs ${hpp})
    list(APPEND py_outputs ${py_dir}/kincal/${type_name}.py)
  endforeach()
  # The Python package in one lcm-gen run: each run appends its type to the package's
  # __init__.py, and runs in parallel (one per type) raced on it, losing lines.
  add_custom_command(
    OUTPUT ${py_outputs}
    COMMAND ${CMAKE_COMMAND} -E make_directory ${py_dir}
    COMMAND ${CMAKE_COMMAND} -E rm -f ${py_dir}/kincal/__init__.py
    COMMAND ${LCM_GEN} --python --ppath ${py_dir} ${sources}
    DEPENDS ${sources}
    COMMENT "lcm-gen the Python package"
    VERBATIM)
  list(APPEND outputs ${py_outputs})
  add_custom_target(${target}_gen DEPENDS ${outputs})
  add_library(${target} INTERFACE)
  add_dependencies(${target} ${target}_gen)
  target_include_directories(${target} SYSTEM INTERFACE ${cpp_dir})
  target_link_libraries(${target} INTERFACE PkgConfig::LCM)
  # lcm-gen 1.3.1 decode() trips a GCC false positive (msg_hash "maybe uninitialized").
  target_compile_options(${target} INTERFACE $<$<CXX_COMPILER_ID:GNU>:-Wno-maybe-uninitialized>)
  add_library(kincal::lcmtypes ALIAS ${target})
  install(DIRECTORY ${cpp_dir}/kincal DESTINATION include/kincal/lcmtypes)
  install(DIRECTORY ${py_dir}/kincal DESTINATION lib/python3/dist-packages)
  # A second copy where the installed scripts look (they run in a venv of their own).
  install(DIRECTORY ${py_dir}/kincal DESTINATION share/kincal/python)
  install(FILES ${sources} DESTINATION share/kincal/lcm)
endfunction()
