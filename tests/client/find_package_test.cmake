# ctest -R client_find_package: install the dnclient component into a fresh
# prefix, then configure, build and run tests/client/consumer against it
# (dn::client, dn::imageio and the C API dn::c), and build its C program once
# more with the installed pkg-config file: cc prog.c $(pkg-config --cflags --libs dn).
foreach(v BUILD_DIR SOURCE_DIR CONSUMER_DIR WORK_DIR GENERATOR)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "find_package_test.cmake: ${v} not set")
  endif()
endforeach()

set(prefix ${WORK_DIR}/prefix)
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})

function(run what)
  execute_process(COMMAND ${ARGN} WORKING_DIRECTORY ${WORK_DIR} RESULT_VARIABLE rc OUTPUT_VARIABLE out
                  ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  set(last_output "${out}" PARENT_SCOPE)
endfunction()

# Runs a consumer program, which must print `expected`.
function(run_consumer what expected)
  run("${what}" ${ARGN})
  string(FIND "${last_output}" "${expected}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "${what} printed:\n${last_output}")
  endif()
  message(STATUS "${last_output}")
endfunction()

run("install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --component dnclient --prefix ${prefix})

foreach(f include/dn/client/client.hpp include/dn/client/session.hpp include/dn/protocol/messages.hpp
          include/dn/protocol/codec.hpp include/dn/image/exr_io.hpp include/dn/image/png.hpp
          include/dn/image/metrics.hpp include/dn/image/pfm.hpp include/dn/dn.h bin/dn)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()
file(GLOB_RECURSE config_files ${prefix}/*/dnclientConfig.cmake)
file(GLOB_RECURSE version_files ${prefix}/*/dnclientConfigVersion.cmake)
file(GLOB_RECURSE target_files ${prefix}/*/dnclientTargets.cmake ${prefix}/*/dnclientImageioTargets.cmake)
file(GLOB_RECURSE pc_files ${prefix}/*/dn.pc)
file(GLOB_RECURSE c_libraries ${prefix}/*/libdn.so)
file(GLOB_RECURSE imageio_libraries ${prefix}/*/libdn_imageio.a)
if(NOT config_files OR NOT version_files OR NOT target_files)
  message(FATAL_ERROR "dnclientConfig.cmake / ConfigVersion / Targets not installed under ${prefix}")
endif()
if(NOT pc_files OR NOT c_libraries OR NOT imageio_libraries)
  message(FATAL_ERROR "dn.pc (${pc_files}), libdn.so (${c_libraries}) or libdn_imageio.a (${imageio_libraries}) "
                      "not installed under ${prefix}")
endif()
foreach(t IN LISTS target_files)
  file(READ ${t} targets_text)
  string(FIND "${targets_text}" "${SOURCE_DIR}" at)
  if(NOT at EQUAL -1)
    message(FATAL_ERROR "installed ${t} refers to the source tree ${SOURCE_DIR}")
  endif()
endforeach()

set(cfg_args -S ${CONSUMER_DIR} -B ${WORK_DIR}/build -G ${GENERATOR} -DCMAKE_PREFIX_PATH=${prefix}
             -DCMAKE_BUILD_TYPE=Release)
if(CXX_COMPILER)
  list(APPEND cfg_args -DCMAKE_CXX_COMPILER=${CXX_COMPILER})
endif()
if(C_COMPILER)
  list(APPEND cfg_args -DCMAKE_C_COMPILER=${C_COMPILER})
endif()
run("consumer configure" ${CMAKE_COMMAND} ${cfg_args})
run("consumer build" ${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run_consumer("consumer run" "dnclient consumer ok" ${WORK_DIR}/build/dnclient_consumer)
run_consumer("C consumer run (dn::c)" "dn c consumer ok" ${WORK_DIR}/build/dnclient_c_consumer)

# pkg-config: the same C program, compiled and linked by hand with the
# installed dn.pc; the rpath is libdn's directory from pkg-config itself.
if(NOT PKG_CONFIG)
  message(FATAL_ERROR "pkg-config not found (scripts/setup.sh installs it); cannot check the installed dn.pc")
endif()
get_filename_component(pc_dir ${pc_files} DIRECTORY)
set(ENV{PKG_CONFIG_PATH} ${pc_dir})
run("pkg-config --cflags --libs dn" ${PKG_CONFIG} --cflags --libs dn)
string(STRIP "${last_output}" pc_flags)
run("pkg-config --variable=libdir dn" ${PKG_CONFIG} --variable=libdir dn)
string(STRIP "${last_output}" pc_libdir)
message(STATUS "pkg-config dn: ${pc_flags}")
if(NOT EXISTS ${pc_libdir}/libdn.so)
  message(FATAL_ERROR "dn.pc's libdir ${pc_libdir} has no libdn.so")
endif()
separate_arguments(pc_flag_list UNIX_COMMAND "${pc_flags}")
if(NOT C_COMPILER)
  set(C_COMPILER cc)
endif()
run("cc c_consumer.c $(pkg-config --cflags --libs dn)" ${C_COMPILER} -std=c99 -Wall -Werror
    ${CONSUMER_DIR}/c_consumer.c ${pc_flag_list} -Wl,-rpath,${pc_libdir} -o ${WORK_DIR}/pkg_config_consumer)
run_consumer("C consumer run (pkg-config)" "dn c consumer ok" ${WORK_DIR}/pkg_config_consumer)
