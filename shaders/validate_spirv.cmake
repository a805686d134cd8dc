# cmake -DSPIRV_VAL=spirv-val -DFILES="a.spv;b.spv" -P validate_spirv.cmake
# Runs spirv-val --target-env vulkan1.2 on every module; fails on the first error.
if(NOT FILES)
  message(FATAL_ERROR "validate_spirv: no SPIR-V files")
endif()
foreach(file IN LISTS FILES)
  execute_process(COMMAND ${SPIRV_VAL} --target-env vulkan1.2 ${file}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "spirv-val failed on ${file}:\n${out}${err}")
  endif()
  message(STATUS "spirv-val ok: ${file}")
endforeach()
