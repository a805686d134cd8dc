# The pipeline families of pipelines.def, for the shader build and dn_pipelines:
#   DN_PIPELINES_DIR      server/pipelines
#   DN_PIPELINE_FOLDERS   stages, then each family of pipelines.def once, in order
# Each folder's *.comp are compiled with the <shader>.pass beside them, its
# *.cpp go into dn_pipelines and its parameters.def rows into the parameter table.
set(DN_PIPELINES_DIR ${CMAKE_CURRENT_LIST_DIR})
set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${DN_PIPELINES_DIR}/pipelines.def)
file(STRINGS ${DN_PIPELINES_DIR}/pipelines.def dn_pipeline_lines REGEX "^DN_PIPELINE\\(")
set(DN_PIPELINE_FOLDERS stages)
foreach(line IN LISTS dn_pipeline_lines)
  string(REGEX REPLACE "^DN_PIPELINE\\(([a-z0-9_]+), *[a-z0-9_]+\\).*" "\\1" family "${line}")
  if(NOT EXISTS ${DN_PIPELINES_DIR}/${family})
    message(FATAL_ERROR "pipelines.def names family '${family}' but server/pipelines/${family}/ does not exist")
  endif()
  list(APPEND DN_PIPELINE_FOLDERS ${family})
endforeach()
list(REMOVE_DUPLICATES DN_PIPELINE_FOLDERS)
