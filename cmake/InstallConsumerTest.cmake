# ctest driver for the installed package, as a user meets it (issue 14):
#  1. cmake --install into a scratch prefix, then move the prefix elsewhere (a relocatable install must not care);
#  2. every installed ELF file carries only $ORIGIN-relative run paths (no build or install paths), and the
#     installed CMake files name no absolute path (Bullet is found on the consumer's machine);
#  3. the installed cullide-pairs runs from the moved prefix on a two-cube scene, without LD_LIBRARY_PATH;
#  4. a separate CMake project finds the package with find_package, builds the culler, the io (readers, PNG) and the
#     two-line-swap applications and runs them, without LD_LIBRARY_PATH;
#  5. the same three applications built with the compiler and `pkg-config --cflags --libs cullide / cullide-io /
#     cullide-bullet` (plus the usual -Wl,-rpath to the package's libdir) run too;
#  6. the culler application (both builds) links only the culler: neither it nor a package library it needs has
#     libpng or libcullide_io among its NEEDED entries, while the io application's do (the check can see them).
# Inputs: BUILD_DIR, SOURCE_DIR (tests/consumer), WORK, CXX (the compiler).
file(REMOVE_RECURSE ${WORK})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK}/staging RESULT_VARIABLE rc
  OUTPUT_QUIET)
if(rc)
  message(FATAL_ERROR "cmake --install failed: ${rc}")
endif()
file(RENAME ${WORK}/staging ${WORK}/prefix)
set(prefix ${WORK}/prefix)

# The library directory as installed (lib, lib64 or lib/<multiarch>, whatever GNUInstallDirs chose).
file(GLOB_RECURSE pcs ${prefix}/*/cullide.pc)
list(LENGTH pcs n)
if(NOT n EQUAL 1)
  message(FATAL_ERROR "expected one installed cullide.pc, found: ${pcs}")
endif()
get_filename_component(pcdir ${pcs} DIRECTORY)
get_filename_component(libdir ${pcdir} DIRECTORY)
foreach(path ${prefix}/bin/cullide-pairs ${prefix}/include/cullide/Culler.h ${prefix}/include/cullide/io/MeshIO.h
    ${prefix}/include/cullide/io/Image.h ${prefix}/include/cullide/io/Snapshot.h
    ${prefix}/include/cullide_bullet/CullideBroadphase.h ${prefix}/share/cullide/shaders/cull.comp
    ${pcdir}/cullide-io.pc ${pcdir}/cullide-bullet.pc ${libdir}/libcullide.so ${libdir}/libcullide_io.so)
  if(NOT EXISTS ${path})
    message(FATAL_ERROR "not installed: ${path}")
  endif()
endforeach()

# The installed CMake files name no path of the build machine: the package's own paths are relative to the
# prefix, Bullet's come from the consumer's own find (CullideBullet::Bullet, made by the config).
file(GLOB cmakes ${libdir}/cmake/CullideBullet/*.cmake)
foreach(f ${cmakes})
  file(STRINGS ${f} lines REGEX "INTERFACE_|IMPORTED_LOCATION|IMPORTED_SONAME")
  foreach(line ${lines})
    if(line MATCHES "[\";]/")
      message(FATAL_ERROR "${f} names an absolute path: ${line}")
    endif()
  endforeach()
endforeach()

# Run paths: only $ORIGIN-relative entries.
file(GLOB elves ${prefix}/bin/* ${libdir}/*.so.*)
foreach(elf ${elves})
  if(IS_SYMLINK ${elf})
    continue()
  endif()
  execute_process(COMMAND readelf -d ${elf} OUTPUT_VARIABLE dyn RESULT_VARIABLE rc)
  if(rc)
    message(FATAL_ERROR "readelf -d ${elf} failed")
  endif()
  string(REGEX MATCHALL "\\((RUNPATH|RPATH)\\)[^\n]*" paths "${dyn}")
  if(NOT paths)
    message(FATAL_ERROR "${elf}: no run path (it would find the package's libraries only through LD_LIBRARY_PATH)")
  endif()
  string(REGEX MATCH "\\[([^]]*)\\]" _ "${paths}")
  string(REPLACE ":" ";" entries "${CMAKE_MATCH_1}")
  foreach(entry ${entries})
    if(NOT entry MATCHES "^\\$ORIGIN")
      message(FATAL_ERROR "${elf}: run path entry '${entry}' is not relative to $ORIGIN")
    endif()
  endforeach()
endforeach()

set(run ${CMAKE_COMMAND} -E env --unset=LD_LIBRARY_PATH --unset=LD_PRELOAD)

# The NEEDED entries of `elf` and, recursively, of every library of the package (in ${libdir}) among them, as
# "file: entry" lines in `out`: what the program makes the loader load from the package, and what those load.
function(needed_closure elf out)
  set(queue ${elf})
  set(seen "")
  set(lines "")
  while(queue)
    list(POP_FRONT queue f)
    list(FIND seen ${f} known)
    if(NOT known EQUAL -1)
      continue()
    endif()
    list(APPEND seen ${f})
    execute_process(COMMAND readelf -d ${f} OUTPUT_VARIABLE dyn RESULT_VARIABLE rc)
    if(rc)
      message(FATAL_ERROR "readelf -d ${f} failed")
    endif()
    string(REGEX MATCHALL "\\(NEEDED\\)[^\n]*\\[[^]\n]*\\]" entries "${dyn}")
    foreach(entry ${entries})
      string(REGEX REPLACE ".*\\[([^]]*)\\]$" "\\1" lib "${entry}")
      get_filename_component(name ${f} NAME)
      list(APPEND lines "${name}: ${lib}")
      if(EXISTS ${libdir}/${lib})
        list(APPEND queue ${libdir}/${lib})
      endif()
    endforeach()
  endwhile()
  set(${out} "${lines}" PARENT_SCOPE)
endfunction()

# An application that links only the culler must not load the io library or libpng; one that links io must (else
# the check could not see them and would pass whatever was linked).
function(check_needed elf kind)
  needed_closure(${elf} lines)
  string(REPLACE ";" "\n  " shown "${lines}")
  if(kind STREQUAL "culler")
    foreach(line ${lines})
      if(line MATCHES "libpng|libcullide_io")
        message(FATAL_ERROR "${elf} links only the culler but needs '${line}'; its NEEDED entries:\n  ${shown}")
      endif()
    endforeach()
  else()
    foreach(want libcullide_io libpng)
      if(NOT lines MATCHES "${want}")
        message(FATAL_ERROR "${elf} uses the io library but needs no ${want}; its NEEDED entries:\n  ${shown}")
      endif()
    endforeach()
  endif()
  message(STATUS "NEEDED of ${elf}: ${lines}")
endfunction()

# The installed program, from the moved prefix.
file(WRITE ${WORK}/cube.off "OFF\n8 12 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
  "3 0 2 1\n3 0 3 2\n3 4 5 6\n3 4 6 7\n3 0 1 5\n3 0 5 4\n3 2 3 7\n3 2 7 6\n3 1 2 6\n3 1 6 5\n3 3 0 4\n3 3 4 7\n")
file(WRITE ${WORK}/scene.json "{\"objects\": [{\"mesh\": \"cube.off\"},
  {\"mesh\": \"cube.off\", \"transform\": [1,0,0,0.5, 0,1,0,0.5, 0,0,1,0.5, 0,0,0,1]}]}")
execute_process(COMMAND ${run} ${prefix}/bin/cullide-pairs ${WORK}/scene.json --gpu-levels never
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc OR NOT out MATCHES "\"object_pairs\": *\\[ *\\[ *0, *1 *\\] *\\]")
  message(FATAL_ERROR "installed cullide-pairs failed (exit ${rc}):\n${out}\n${err}")
endif()
message(STATUS "installed cullide-pairs ran from the moved prefix")

# find_package consumer.
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK}/build -DCMAKE_PREFIX_PATH=${prefix}
  RESULT_VARIABLE rc)
if(rc)
  message(FATAL_ERROR "configuring the consumer failed")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK}/build RESULT_VARIABLE rc)
if(rc)
  message(FATAL_ERROR "building the consumer failed")
endif()
set(args_consumer "")
set(args_consumer_io ${WORK}/cube.off ${WORK}/consumer_io.png)
set(args_consumer_bullet "")
foreach(exe consumer consumer_io consumer_bullet)
  execute_process(COMMAND ${run} ${WORK}/build/${exe} ${args_${exe}} RESULT_VARIABLE rc)
  if(rc)
    message(FATAL_ERROR "${exe} (find_package) failed: ${rc}")
  endif()
endforeach()
check_needed(${WORK}/build/consumer culler)
check_needed(${WORK}/build/consumer_io io)

# pkg-config consumer: the compiler line a Makefile user writes.
foreach(pair "consumer;cullide" "consumer_io;cullide-io" "consumer_bullet;cullide-bullet")
  list(GET pair 0 exe)
  list(GET pair 1 module)
  execute_process(COMMAND ${CMAKE_COMMAND} -E env PKG_CONFIG_PATH=${pcdir}
    pkg-config --cflags --libs ${module} OUTPUT_VARIABLE flags RESULT_VARIABLE rc OUTPUT_STRIP_TRAILING_WHITESPACE)
  execute_process(COMMAND ${CMAKE_COMMAND} -E env PKG_CONFIG_PATH=${pcdir}
    pkg-config --variable=libdir ${module} OUTPUT_VARIABLE pclibdir OUTPUT_STRIP_TRAILING_WHITESPACE)
  if(rc)
    message(FATAL_ERROR "pkg-config ${module} failed")
  endif()
  separate_arguments(flags UNIX_COMMAND "${flags}")
  execute_process(COMMAND ${CXX} -std=c++17 ${SOURCE_DIR}/${exe}.cpp -o ${WORK}/${exe}_pc ${flags}
    -Wl,-rpath,${pclibdir} RESULT_VARIABLE rc)
  if(rc)
    message(FATAL_ERROR "building ${exe} with pkg-config ${module} failed: ${CXX} ${flags}")
  endif()
  execute_process(COMMAND ${run} ${WORK}/${exe}_pc ${args_${exe}} RESULT_VARIABLE rc)
  if(rc)
    message(FATAL_ERROR "${exe} (pkg-config) failed: ${rc}")
  endif()
endforeach()
check_needed(${WORK}/consumer_pc culler)
# cullide.pc names nothing of the io library, not even for static linking.
execute_process(COMMAND ${CMAKE_COMMAND} -E env PKG_CONFIG_PATH=${pcdir}
  pkg-config --cflags --libs --static cullide OUTPUT_VARIABLE flags RESULT_VARIABLE rc OUTPUT_STRIP_TRAILING_WHITESPACE)
if(rc OR flags MATCHES "png|cullide_io")
  message(FATAL_ERROR "pkg-config --static cullide (exit ${rc}) names the io library or libpng: ${flags}")
endif()
check_needed(${WORK}/consumer_io_pc io)
