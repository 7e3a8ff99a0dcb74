# The frame cache's renderer identity (cmake/DriftlabRendererIdentity.cmake): the
# build hashes every file that decides a frame's bytes, so that a change to a shader, scene or
# camera effect makes every cached frame a miss. Checked here:
#   1. the build's list names the renderer, its shaders, the scene builders, the textures and
#      the camera effects (a list without them would serve stale frames);
#   2. the identity is the same for the same files (and the generated source is not rewritten,
#      so nothing recompiles), and changes when one byte of one file or the build changes.
# cmake -DSOURCE_DIR=... -DLIST_FILE=BUILD/pipeline/frame_sources.txt -DWORK=DIR -P this file
cmake_minimum_required(VERSION 3.21)
foreach(var SOURCE_DIR LIST_FILE WORK)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "-D${var}=... is required")
  endif()
endforeach()
set(script ${SOURCE_DIR}/cmake/DriftlabRendererIdentity.cmake)

# 1. What the build hashes.
file(STRINGS "${LIST_FILE}" listed)
foreach(f sim/render/renderer.cpp sim/render/shaders.hpp sim/render/gl_context.cpp
          sim/sensors/camera_effects.cpp sim/sensors/lens.cpp sim/physics/waves/wave_field.cpp
          scenes/build_scene.cpp scenes/textures.cpp scenes/river_reach.cpp
          pipeline/camera_stage.cpp pipeline/frame_source.cpp pipeline/render_stage.cpp
          pipeline/frame_cache_key.cpp core/rng.cpp)
  if(NOT f IN_LIST listed)
    message(FATAL_ERROR "${LIST_FILE} does not name ${f}: a change to it would not change the "
                        "renderer identity")
  endif()
endforeach()
foreach(f vo/sparse/sparse_vo.cpp eval/evaluate.cpp pipeline/run.cpp)
  if(f IN_LIST listed)
    message(FATAL_ERROR "${LIST_FILE} names ${f}, which decides no frame: every change to it "
                        "would throw the frame cache away")
  endif()
endforeach()

# 2. The identity of two small files as the build computes it.
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}/src/sim")
file(WRITE "${WORK}/src/sim/a.hpp" "// a shader\nconst char* kShader = \"gl_FragColor\";\n")
file(WRITE "${WORK}/src/sim/b.cpp" "int b() { return 1; }\n")
file(WRITE "${WORK}/list.txt" "sim/a.hpp\nsim/b.cpp\n")
function(identity build out_var)
  execute_process(COMMAND ${CMAKE_COMMAND} -DSOURCE_DIR=${WORK}/src -DLIST_FILE=${WORK}/list.txt
                          "-DBUILD_TEXT=${build}" -DOUT=${WORK}/id.cpp -P ${script}
                  RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "the identity script failed: ${rc}")
  endif()
  file(READ "${WORK}/id.cpp" text)
  string(REGEX MATCH "return \"([0-9a-f]+) \\(2 files\\)\"" found "${text}")
  if(NOT found)
    message(FATAL_ERROR "no identity of 2 files in the generated source:\n${text}")
  endif()
  set(${out_var} "${CMAKE_MATCH_1}" PARENT_SCOPE)
endfunction()

identity("GNU 12 Release -O3" first)
file(TIMESTAMP "${WORK}/id.cpp" written "%s")
execute_process(COMMAND ${CMAKE_COMMAND} -E sleep 1.1)
identity("GNU 12 Release -O3" again)
file(TIMESTAMP "${WORK}/id.cpp" rewritten "%s")
if(NOT first STREQUAL again OR NOT written STREQUAL rewritten)
  message(FATAL_ERROR "the same files gave ${first} then ${again} (written ${written}, "
                      "${rewritten})")
endif()
file(WRITE "${WORK}/src/sim/a.hpp" "// a shader\nconst char* kShader = \"gl_FragColoR\";\n")
identity("GNU 12 Release -O3" shader_changed)
if(shader_changed STREQUAL first)
  message(FATAL_ERROR "a changed shader kept the identity ${first}")
endif()
identity("GNU 12 Debug -O0" build_changed)
if(build_changed STREQUAL shader_changed)
  message(FATAL_ERROR "another build kept the identity ${shader_changed}")
endif()
file(REMOVE_RECURSE "${WORK}")
message(STATUS "renderer identity: ${first} -> ${shader_changed} -> ${build_changed}")
