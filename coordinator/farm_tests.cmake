# Links the farm's tests (tests/farm_*_test.cpp) and benchmark (tests/bench/farm_bench.cpp) with the farm
# libraries and makes them depend on the executables they start. Included from the top-level
# CMakeLists.txt after tests/ (the targets are created there by the generic per-file loop).
file(GLOB MLTFARM_FARM_TESTS CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/tests/farm_*_test.cpp
     ${PROJECT_SOURCE_DIR}/tests/bench/farm*_bench.cpp)
foreach(src ${MLTFARM_FARM_TESTS})
  get_filename_component(name ${src} NAME_WE)
  if(TARGET ${name})
    target_link_libraries(${name} PRIVATE mltfarm_worker mltfarm_coord)
    add_dependencies(${name} mltfarm mltfarm-coordinator mltfarm-worker)
    target_compile_definitions(${name} PRIVATE MLTFARM_TOOLS_DIR="${CMAKE_BINARY_DIR}/tools")
  endif()
endforeach()

# deploy/slurm/mltfarm.sbatch on a one-node Slurm cluster started by the script (exit 77 = skipped, with
# the reason, when the daemons cannot run on this machine).
if(TARGET mltfarm)
  add_test(NAME farm_slurm_local
           COMMAND bash ${PROJECT_SOURCE_DIR}/tests/farm/slurm_local_test.sh ${CMAKE_BINARY_DIR}/tools)
  set_tests_properties(farm_slurm_local PROPERTIES SKIP_RETURN_CODE 77 TIMEOUT 600 RUN_SERIAL TRUE)
endif()

# The web page in a real headless Chromium (tests/farm/browser_test.py; exit 77 = skipped, with the
# reason, when no Chromium is installed). Its screenshot of a job page goes to BUILD/screenshots/.
if(TARGET mltfarm)
  add_test(NAME farm_browser
           COMMAND python3 ${PROJECT_SOURCE_DIR}/tests/farm/browser_test.py ${CMAKE_BINARY_DIR}/tools
                   ${PROJECT_SOURCE_DIR} ${CMAKE_BINARY_DIR}/screenshots/job-page.png)
  set_tests_properties(farm_browser PROPERTIES SKIP_RETURN_CODE 77 TIMEOUT 600 RUN_SERIAL TRUE)
endif()

# deploy/k8s/*.yaml against the Kubernetes API schema, offline (npm's kubernetes-models; exit 77 = skipped
# without node/npm), and the Docker image built from the repository (exit 77 without a working engine).
add_test(NAME farm_k8s_manifests
         COMMAND bash ${PROJECT_SOURCE_DIR}/tests/farm/k8s_manifests_test.sh ${PROJECT_SOURCE_DIR}
                 ${CMAKE_BINARY_DIR}/k8s-validate)
set_tests_properties(farm_k8s_manifests PROPERTIES SKIP_RETURN_CODE 77 TIMEOUT 600)
add_test(NAME farm_docker_image COMMAND bash ${PROJECT_SOURCE_DIR}/tests/farm/docker_image_test.sh ${PROJECT_SOURCE_DIR})
set_tests_properties(farm_docker_image PROPERTIES SKIP_RETURN_CODE 77 TIMEOUT 3600 RUN_SERIAL TRUE)
