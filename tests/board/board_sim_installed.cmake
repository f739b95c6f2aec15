# tripodal-board-sim as installed: the program copied to PREFIX/bin with a world at
# PREFIX/share/tripodal/configs/worlds/workspace.yaml takes that world by default (not the source
# tree's, not ./configs). The world put there is broken on purpose, so the program names the file
# it loaded in its error. Arguments: EXE, PREFIX.
file(REMOVE_RECURSE ${PREFIX})
file(MAKE_DIRECTORY ${PREFIX}/bin ${PREFIX}/share/tripodal/configs/worlds)
file(COPY ${EXE} DESTINATION ${PREFIX}/bin)
file(WRITE ${PREFIX}/share/tripodal/configs/worlds/workspace.yaml "map: missing_map.yaml\nstart_pose: [1, 1]\n")
get_filename_component(_name ${EXE} NAME)
execute_process(COMMAND ${PREFIX}/bin/${_name} --duration-s 0.1 WORKING_DIRECTORY ${PREFIX}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}${err}")
if(NOT rc EQUAL 1)
  message(FATAL_ERROR "exit code ${rc}, expected 1")
endif()
