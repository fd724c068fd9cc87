# One deterministic regression run of a fuzz target: the committed corpus, then RUNS mutations
# from seed 1. New inputs and artifacts go to SCRATCH (emptied first), never to the corpus.
# Deterministic: fixed seed, a fixed work directory, and -use_cmp=0 (comparison operands include
# addresses, which ASLR changes from run to run).
file(REMOVE_RECURSE "${SCRATCH}")
file(MAKE_DIRECTORY "${SCRATCH}/new")
set(args -runs=${RUNS} -seed=1 -use_cmp=0 -rss_limit_mb=2048 -timeout=20 -max_len=4096 -print_final_stats=1
  -artifact_prefix=${SCRATCH}/)
if(DICT)
  list(APPEND args ${DICT})
endif()
set(ENV{KESTREL_FUZZ_WORK_DIR} "${SCRATCH}/work")
execute_process(COMMAND ${FUZZER} ${args} ${SCRATCH}/new ${CORPUS} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${FUZZER} failed (exit ${rc}); the crashing input is in ${SCRATCH}/ (crash-*, timeout-*, oom-*)")
endif()
