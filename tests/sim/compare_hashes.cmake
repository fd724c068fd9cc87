# Runs `kestrel run` (the default scenario, or -DSCENARIO=FILE) three times (1 thread, 2 threads, 2 threads again) and checks the final
# state hashes are equal: bit-identical across thread counts and runs.
set(hashes "")
foreach(t 1 2 2)
  # SCENARIO (optional): a scenario file to run instead of the default one.
  execute_process(COMMAND ${KESTREL} run ${SCENARIO} --envs 64 --steps 200 --threads ${t} --out ${OUT}
                  OUTPUT_VARIABLE out RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "kestrel run failed (${rc}):\n${out}")
  endif()
  string(REGEX MATCH "state hash: ([0-9a-f]+)" m "${out}")
  list(APPEND hashes "${CMAKE_MATCH_1}")
endforeach()
list(REMOVE_DUPLICATES hashes)
list(LENGTH hashes n)
if(NOT n EQUAL 1)
  message(FATAL_ERROR "state hashes differ: ${hashes}")
endif()
message(STATUS "state hash ${hashes} for 1, 2, 2 threads")
