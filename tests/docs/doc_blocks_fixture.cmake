# Runs scripts/doc_blocks.py check on tests/data/docs/wrong_blocks, whose doc has one wrong block of
# each kind: it must fail and name each at its line; the good excerpt (with `...`) passes.
#   cmake -DPYTHON=... -DSCRIPT=... -DROOT=... -P doc_blocks_fixture.cmake
execute_process(COMMAND ${PYTHON} ${SCRIPT} --root ${ROOT} check RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 1)
  message(FATAL_ERROR "doc_blocks.py exited ${rc}, expected 1:\n${out}${err}")
endif()
foreach(expected
    "docs/blocks.md:3: a cpp block without a marker"
    "docs/blocks.md:8: line 10 ('const int y = 3 * x;') is not in examples/part.cpp"
    "docs/blocks.md:23: a fragment says why it is not checked"
    "docs/blocks.md:28: unknown doc-block kind 'guess'"
    "docs/blocks.md:33: not YAML"
    "docs/blocks.md:38: doc-block 'main' is for cpp blocks, this one is yaml"
    "docs/blocks.md:43: 'bye' (the output shown after the command of line 44) is not in what it prints (exit 0)"
    "docs/blocks.md:49: the commands exit 1")
  string(FIND "${out}" "${expected}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "doc_blocks.py did not report: ${expected}\nit reported:\n${out}")
  endif()
endforeach()
string(FIND "${out}" "docs/blocks.md:13:" at)
if(NOT at EQUAL -1)
  message(FATAL_ERROR "doc_blocks.py refused the excerpt with `...` (docs/blocks.md:13):\n${out}")
endif()
if(NOT err MATCHES "5 marked blocks \\(2 excerpt, 1 shell, 1 transcript, 1 yaml\\); 8 problems")
  message(FATAL_ERROR "unexpected summary:\n${err}")
endif()
