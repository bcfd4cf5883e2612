# libwoven.so: the library for other languages (include/woven/ffi.h; the Python package
# in python/ loads it). The same sources as woven_lib, compiled again as position-independent
# code, so the static library and the CLI keep their code generation.
get_target_property(_wv_sources woven_lib SOURCES)
get_target_property(_wv_includes woven_lib INCLUDE_DIRECTORIES)
get_target_property(_wv_defs woven_lib COMPILE_DEFINITIONS)
get_target_property(_wv_libs woven_lib LINK_LIBRARIES)
add_library(woven_shared SHARED ${_wv_sources})
add_dependencies(woven_shared woven_assets)
set_target_properties(woven_shared PROPERTIES OUTPUT_NAME woven)
target_include_directories(woven_shared PRIVATE ${_wv_includes})
if(_wv_defs)
  target_compile_definitions(woven_shared PRIVATE ${_wv_defs})
endif()
target_link_libraries(woven_shared PRIVATE ${_wv_libs})
