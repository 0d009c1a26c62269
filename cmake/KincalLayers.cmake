# The layers of kincal, lowest first, and what each may include and link: the one place
# that says it. Each layer is a library (src/<layer>/ with its private headers,
# include/kincal/<layer>/ public; core's public headers sit directly in include/kincal/).
# CMakeLists.txt builds the libraries from this list; cmake/CheckLayers.cmake fails the
# build on an include that runs up a layer or into another layer's private headers.
set(KINCAL_LAYERS core io estimation vision sim analysis plan online daemon)
set(KINCAL_LAYER_core_USES "")
set(KINCAL_LAYER_io_USES core)
set(KINCAL_LAYER_estimation_USES core)
set(KINCAL_LAYER_vision_USES core io estimation)
set(KINCAL_LAYER_sim_USES core estimation vision)
set(KINCAL_LAYER_analysis_USES core io estimation)
set(KINCAL_LAYER_plan_USES core io estimation vision sim)
set(KINCAL_LAYER_online_USES core io estimation vision sim analysis plan)
set(KINCAL_LAYER_daemon_USES core io estimation vision sim analysis plan online)
