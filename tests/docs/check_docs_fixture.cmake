# Runs scripts/check_docs.py on tests/data/docs/wrong_tree, whose docs name what the tree does not
# have: it must fail and report each kind of mistake at its line.
#   cmake -DPYTHON=... -DSCRIPT=... -DROOT=... -P check_docs_fixture.cmake
execute_process(COMMAND ${PYTHON} ${SCRIPT} --root ${ROOT} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 1)
  message(FATAL_ERROR "check_docs.py exited ${rc}, expected 1:\n${out}${err}")
endif()
foreach(expected
    "docs/wrong.md:3: names 'src/robot/missing_loader.cpp', which does not exist"
    "docs/wrong.md:4: names 'NoSuchType', which no source declares or registers"
    "docs/wrong.md:5: names profile key 'plugins:', which no loader or configuration knows"
    "docs/wrong.md:6: links to 'other.md', which does not exist"
    "docs/wrong.md:7: names header 'tripodal/robot/gone.hpp', which include/ does not have"
    "docs/wrong.md:11: behavior 'BhWrong' declares output 'cmd_vel'; a behavior writes 'behavior_command'")
  string(FIND "${out}" "${expected}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "check_docs.py did not report: ${expected}\nit reported:\n${out}")
  endif()
endforeach()
foreach(unexpected "RealType" "OldName" "behaviors:")
  string(FIND "${out}" "'${unexpected}" at)
  if(NOT at EQUAL -1)
    message(FATAL_ERROR "check_docs.py reported '${unexpected}', which the fixture has:\n${out}")
  endif()
endforeach()
