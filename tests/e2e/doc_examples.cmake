# docs/client.md's C++ examples as programs: every ```cpp block is extracted
# at configure time (CMake re-runs when the page changes) into its own
# executable linked against dn::client, with #line pointing back at the page
# so a compile error names docs/client.md and its line; every ```c block
# likewise into a C99 program (compiled as C, -Wall -Werror) linked against
# the C API dn::c. A block that stops compiling fails the build;
# doc_examples_test.cpp runs each one against a real dnserver and fails when
# one exits non-zero.
set(dn_doc ${PROJECT_SOURCE_DIR}/docs/client.md)
set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${dn_doc})
file(READ ${dn_doc} dn_doc_text)
set(dn_doc_dir ${CMAKE_CURRENT_BINARY_DIR}/doc_examples)
file(MAKE_DIRECTORY ${dn_doc_dir})
set(dn_doc_example_targets "")

# Extracts the ```<lang> blocks into <name>_<n>.<ext> programs linked to
# <link>; writes {path, line} per example to doc_examples<inc_suffix>.inc.
function(dn_doc_examples lang ext link inc_suffix)
  set(dn_open "```${lang}\n")
  string(LENGTH "${dn_open}" dn_open_length)
  set(dn_close "\n```")
  set(dn_doc_examples "")
  set(dn_targets "")
  set(dn_offset 0)
  set(dn_index 0)
  while(TRUE)
    # Only string(FIND/SUBSTRING) on the text: C++ is full of ';', which CMake list commands would split.
    string(SUBSTRING "${dn_doc_text}" ${dn_offset} -1 dn_rest)
    string(FIND "${dn_rest}" "${dn_open}" dn_start)
    if(dn_start EQUAL -1)
      break()
    endif()
    math(EXPR dn_code_start "${dn_start} + ${dn_open_length}")
    string(SUBSTRING "${dn_rest}" ${dn_code_start} -1 dn_code_rest)
    string(FIND "${dn_code_rest}" "${dn_close}" dn_length)
    if(dn_length EQUAL -1)
      message(FATAL_ERROR "docs/client.md: a ```${lang} block is not closed")
    endif()
    string(SUBSTRING "${dn_code_rest}" 0 ${dn_length} dn_code)
    # Line of the block's first code line: newlines before it, plus one.
    math(EXPR dn_before "${dn_offset} + ${dn_code_start}")
    string(SUBSTRING "${dn_doc_text}" 0 ${dn_before} dn_prefix)
    string(REGEX REPLACE "[^\n]" "" dn_newlines "${dn_prefix}")
    string(LENGTH "${dn_newlines}" dn_line)
    math(EXPR dn_line "${dn_line} + 1")

    math(EXPR dn_index "${dn_index} + 1")
    set(dn_name doc_example_client_md${inc_suffix}_${dn_index})
    set(dn_source ${dn_doc_dir}/client_md${inc_suffix}_${dn_index}.${ext})
    file(WRITE ${dn_source}.new "#line ${dn_line} \"${dn_doc}\"\n${dn_code}\n")
    file(COPY_FILE ${dn_source}.new ${dn_source} ONLY_IF_DIFFERENT)  # no rebuild when unchanged
    file(REMOVE ${dn_source}.new)
    add_executable(${dn_name} ${dn_source})
    target_link_libraries(${dn_name} PRIVATE ${link})
    if(ext STREQUAL "c")
      set_target_properties(${dn_name} PROPERTIES C_STANDARD 99 C_STANDARD_REQUIRED ON C_EXTENSIONS OFF)
      target_compile_options(${dn_name} PRIVATE -Wall -Wextra -Werror)
    endif()
    list(APPEND dn_targets ${dn_name})
    # The sources too, for tests that build them another way (tests/capi: with pkg-config).
    set_property(GLOBAL APPEND PROPERTY DN_DOC_EXAMPLE_SOURCES_${ext} ${dn_source})
    string(APPEND dn_doc_examples "{\"$<TARGET_FILE:${dn_name}>\", ${dn_line}},\n")

    math(EXPR dn_offset "${dn_offset} + ${dn_code_start} + ${dn_length} + 4")
  endwhile()
  if(dn_index EQUAL 0)
    message(FATAL_ERROR "docs/client.md: no ```${lang} example found; DocExamples would test nothing")
  endif()
  # {path, line in docs/client.md} per example, included by doc_examples_test.cpp.
  file(GENERATE OUTPUT ${dn_doc_dir}/doc_examples${inc_suffix}.inc CONTENT "${dn_doc_examples}")
  set(dn_doc_example_targets ${dn_doc_example_targets} ${dn_targets} PARENT_SCOPE)
endfunction()

dn_doc_examples(cpp cpp dn::client "")
dn_doc_examples(c c dn::c "_c")
