# The allowed dependency directions between the project's modules (docs/architecture.md), checked at
# configure time: a module's library links, and its sources include headers of, only the modules
# listed for it. Adding an arrow is a design decision: change it here and in docs/architecture.md.
#
# A module <m>_research is the folder <m>/research/ (library furuta_<m>_research, headers
# furuta/<m>/research/): what only bench/ and tests/ use. No module lists it, so no product library
# links it or includes its headers; the sources under <m>/research/ are its own, not <m>'s.

set(FURUTA_MODULE_DEPENDENCIES
  "common:"
  "model:"
  "control:model"
  "interval:common"
  "firmware_bridge:"
  "simulator:firmware_bridge,model"
  "config:firmware_bridge,simulator,model,control"
  "lcmtypes:"
  "command_auth:lcmtypes,common"
  "session_log:lcmtypes,firmware_bridge"
  "daemon:firmware_bridge,simulator,config,session_log,lcmtypes,model,control,command_auth,common"
  "identification:model,interval,config,session_log,validated"
  "validated:model,interval,common"
  "validated_research:validated,model,interval,common"
  "pipeline:identification,validated,session_log,config,model,interval"
  "report:pipeline,identification,validated,verification,session_log,config,model,interval,common"
  "app:control,firmware_bridge,simulator,config,daemon,command_auth,session_log,identification,validated,pipeline,report,model,interval,common,lcmtypes"
)

function(furuta_check_module_dependencies)
  set(modules "")
  set(folders "")
  foreach(entry IN LISTS FURUTA_MODULE_DEPENDENCIES)
    string(REPLACE ":" ";" parts "${entry}")
    list(GET parts 0 module)
    list(LENGTH parts n)
    set(allowed "")
    if(n GREATER 1)
      list(GET parts 1 allowed_text)
      string(REPLACE "," ";" allowed "${allowed_text}")
    endif()
    set(allowed_${module} "${allowed}")
    string(REGEX REPLACE "_research$" "/research" folder_${module} ${module})
    list(APPEND modules ${module})
    list(APPEND folders ${folder_${module}})
  endforeach()

  foreach(module IN LISTS modules)
    set(target furuta_${module})
    set(folder ${folder_${module}})
    if(NOT TARGET ${target} OR NOT IS_DIRECTORY ${PROJECT_SOURCE_DIR}/${folder})
      continue()
    endif()
    # Links: every furuta library named in the module's own link lists.
    get_target_property(type ${target} TYPE)
    set(links "")
    if(NOT type STREQUAL "INTERFACE_LIBRARY")
      get_target_property(private_links ${target} LINK_LIBRARIES)
      if(private_links)
        list(APPEND links ${private_links})
      endif()
    endif()
    get_target_property(interface_links ${target} INTERFACE_LINK_LIBRARIES)
    if(interface_links)
      list(APPEND links ${interface_links})
    endif()
    foreach(link IN LISTS links)
      if(link MATCHES "^(\\$<LINK_ONLY:)?furuta(::|_)([a-z_]+)>?$")
        set(dep ${CMAKE_MATCH_3})
        if(NOT dep STREQUAL module AND NOT dep IN_LIST allowed_${module})
          message(FATAL_ERROR "module ${module} links furuta::${dep}, which it may not "
                              "(cmake/ModuleDependencies.cmake, docs/architecture.md)")
        endif()
      endif()
    endforeach()
    # Includes: every "furuta/<module>/..." header named by the module's sources (those in a
    # module folder inside this one are that module's).
    file(GLOB_RECURSE sources ${PROJECT_SOURCE_DIR}/${folder}/*.cpp ${PROJECT_SOURCE_DIR}/${folder}/*.hpp)
    foreach(inner IN LISTS folders)
      if(inner MATCHES "^${folder}/")
        list(FILTER sources EXCLUDE REGEX "^${PROJECT_SOURCE_DIR}/${inner}/")
      endif()
    endforeach()
    foreach(source IN LISTS sources)
      file(STRINGS ${source} includes REGEX "^#include [<\"]furuta/")
      foreach(line IN LISTS includes)
        if(line MATCHES "^#include [<\"]furuta/(([a-z_]+)/research)/")
          set(dep ${CMAKE_MATCH_2}_research)
        elseif(line MATCHES "^#include [<\"]furuta/([a-z_]+)/")
          set(dep ${CMAKE_MATCH_1})
        else()
          continue()
        endif()
        if(NOT dep STREQUAL module AND NOT dep IN_LIST allowed_${module})
          file(RELATIVE_PATH where ${PROJECT_SOURCE_DIR} ${source})
          message(FATAL_ERROR "${where} includes furuta/${CMAKE_MATCH_1}/, which module ${module} "
                              "may not use (cmake/ModuleDependencies.cmake, docs/architecture.md)")
        endif()
      endforeach()
    endforeach()
  endforeach()
endfunction()
