# The OpenCV modules ovton uses, as the targets opencv_<module> and OpenCV_LIBS / OpenCV_INCLUDE_DIRS.
# Debian ships OpenCVConfig.cmake only in the libopencv-dev metapackage, which pulls in every module and what those need
# (Qt, GDAL, FFmpeg, ...). scripts/install_deps.sh --minimal installs just the modules' own -dev packages; then the
# libraries and headers are found one by one here. Used by the build and by the installed ovtonConfig.cmake.
set(OVTON_OPENCV_MODULES core imgproc imgcodecs video features2d calib3d)
if(NOT OVTON_OPENCV_BY_MODULE)
  find_package(OpenCV QUIET COMPONENTS ${OVTON_OPENCV_MODULES})
endif()
if(NOT OpenCV_FOUND)
  find_path(OVTON_OPENCV_INCLUDE_DIR opencv2/core.hpp PATH_SUFFIXES opencv4)
  if(NOT OVTON_OPENCV_INCLUDE_DIR)
    message(FATAL_ERROR "OpenCV not found: install libopencv-dev, or the modules' packages (scripts/install_deps.sh "
                        "--minimal: libopencv-{core,imgproc,imgcodecs,video,features2d,calib3d}-dev)")
  endif()
  set(OpenCV_INCLUDE_DIRS ${OVTON_OPENCV_INCLUDE_DIR})
  set(OpenCV_LIBS)
  foreach(module ${OVTON_OPENCV_MODULES})
    if(NOT TARGET opencv_${module})
      find_library(OVTON_OPENCV_${module}_LIBRARY opencv_${module})
      if(NOT OVTON_OPENCV_${module}_LIBRARY)
        message(FATAL_ERROR "OpenCV module ${module} not found (Debian: libopencv-${module}-dev)")
      endif()
      add_library(opencv_${module} SHARED IMPORTED)
      set_target_properties(opencv_${module} PROPERTIES IMPORTED_LOCATION ${OVTON_OPENCV_${module}_LIBRARY}
                                                        INTERFACE_INCLUDE_DIRECTORIES ${OVTON_OPENCV_INCLUDE_DIR})
    endif()
    list(APPEND OpenCV_LIBS opencv_${module})
  endforeach()
  set(OpenCV_FOUND TRUE)
  message(STATUS "OpenCV: modules found one by one in ${OVTON_OPENCV_INCLUDE_DIR} (no OpenCVConfig.cmake)")
endif()
