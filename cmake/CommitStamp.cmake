# The commit behind a build (core/version.h), read at every build rather than when the build folder was
# configured, so that a rebuild after a commit names the new commit. Included for its function; run
# as a script (cmake -P) by the target that function adds:
#
#   cmake -DSOURCE_DIR=<tree> -DTEMPLATE=<file.cc.in> -DOUTPUT=<file.cc> -P CommitStamp.cmake
#
# writes OUTPUT from TEMPLATE with @WEATHERGS_SOURCE_COMMIT@ = git's short hash of SOURCE_DIR's HEAD,
# "-dirty" appended when tracked files under SOURCE_DIR differ from it, "unknown" outside a git
# checkout. configure_file leaves an unchanged OUTPUT untouched, so a build on the same commit
# recompiles and relinks nothing.
if(CMAKE_SCRIPT_MODE_FILE)
  foreach(var SOURCE_DIR TEMPLATE OUTPUT)
    if(NOT DEFINED ${var})
      message(FATAL_ERROR "CommitStamp.cmake: -D${var}=... is required")
    endif()
  endforeach()
  find_program(GIT_EXECUTABLE git)
  set(WEATHERGS_SOURCE_COMMIT unknown)
  if(GIT_EXECUTABLE)
    execute_process(COMMAND ${GIT_EXECUTABLE} rev-parse --short HEAD WORKING_DIRECTORY ${SOURCE_DIR}
                    OUTPUT_VARIABLE commit OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET RESULT_VARIABLE git_rc)
    if(git_rc EQUAL 0 AND NOT commit STREQUAL "")
      set(WEATHERGS_SOURCE_COMMIT ${commit})
      # --no-optional-locks: a build must not take the index lock from a commit running beside it.
      execute_process(COMMAND ${GIT_EXECUTABLE} --no-optional-locks diff --quiet HEAD -- .
                      WORKING_DIRECTORY ${SOURCE_DIR} RESULT_VARIABLE dirty_rc ERROR_QUIET)
      if(NOT dirty_rc EQUAL 0)
        string(APPEND WEATHERGS_SOURCE_COMMIT "-dirty")
      endif()
    endif()
  endif()
  configure_file(${TEMPLATE} ${OUTPUT} @ONLY)
  return()
endif()

set(WEATHERGS_COMMIT_STAMP_SCRIPT ${CMAKE_CURRENT_LIST_FILE})

# weathergs_commit_stamp(NAME target TEMPLATE file.cc.in OUTPUT file.cc SOURCE_DIR tree): OUTPUT written
# now (so that it exists for the first build) and by `target`, which runs at every build. A library
# that compiles OUTPUT adds `add_dependencies(<library> target)`.
function(weathergs_commit_stamp)
  cmake_parse_arguments(ARG "" "NAME;TEMPLATE;OUTPUT;SOURCE_DIR" "" ${ARGN})
  set(args -DSOURCE_DIR=${ARG_SOURCE_DIR} -DTEMPLATE=${ARG_TEMPLATE} -DOUTPUT=${ARG_OUTPUT}
           -P ${WEATHERGS_COMMIT_STAMP_SCRIPT})
  execute_process(COMMAND ${CMAKE_COMMAND} ${args} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "the commit stamp of ${ARG_OUTPUT} could not be written")
  endif()
  # BYPRODUCTS: Ninja rechecks OUTPUT's time after the command, so an unchanged file rebuilds nothing.
  add_custom_target(${ARG_NAME} COMMAND ${CMAKE_COMMAND} ${args} BYPRODUCTS ${ARG_OUTPUT} VERBATIM)
endfunction()
