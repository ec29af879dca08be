# Looks for what the tests and benchmarks need beyond the serving packages and lists what is
# missing in PINTAG_MISSING_TEST_PACKAGES, each with the Debian package that brings it
# (scripts/debian-packages-test.txt). Found packages stay loaded for tests/ and bench/: apriltag
# in particular is loaded once here, in the top directory, because Debian's config cannot be
# loaded again from a second subdirectory once it made apriltag::apriltag global.
set(PINTAG_MISSING_TEST_PACKAGES)
macro(pintag_tests_need found what)
  if(NOT ${found})
    list(APPEND PINTAG_MISSING_TEST_PACKAGES "${what}")
  endif()
endmacro()

find_package(GTest QUIET)
pintag_tests_need(GTest_FOUND "GoogleTest (libgtest-dev, libgmock-dev)")
find_package(benchmark QUIET)
pintag_tests_need(benchmark_FOUND "Google Benchmark (libbenchmark-dev)")
find_package(apriltag CONFIG QUIET)
pintag_tests_need(apriltag_FOUND "AprilTag (libapriltag-dev)")
find_package(OpenCV QUIET COMPONENTS aruco)
pintag_tests_need(OpenCV_FOUND "OpenCV ArUco (libopencv-contrib-dev)")
find_program(PINTAG_PDFTOTEXT pdftotext)
pintag_tests_need(PINTAG_PDFTOTEXT "pdfinfo and pdftotext (poppler-utils)")
find_program(PINTAG_NODE node)
pintag_tests_need(PINTAG_NODE "node, for the browser tests (nodejs)")
find_program(PINTAG_NPM npm)
pintag_tests_need(PINTAG_NPM "npm, for the browser tests (npm)")
find_program(PINTAG_CHROMIUM chromium)
pintag_tests_need(PINTAG_CHROMIUM "Chromium, for the browser tests (chromium)")
find_program(PINTAG_SS ss)
pintag_tests_need(PINTAG_SS "ss, for the listen backlog test (iproute2)")
find_program(PINTAG_NGINX nginx PATHS /usr/sbin)
pintag_tests_need(PINTAG_NGINX "nginx, for the scale-out test (nginx-light)")
find_package(PkgConfig QUIET)
if(PkgConfig_FOUND)
  pkg_check_modules(PINTAG_TURBOJPEG QUIET libturbojpeg)
endif()
pintag_tests_need(PINTAG_TURBOJPEG_FOUND "TurboJPEG (libturbojpeg0-dev)")
# The scene backgrounds (tests/scene/src/background.cpp): one file of each package stands for it.
foreach(photo "opencv-doc:/usr/share/doc/opencv-doc/examples/data/fruits.jpg"
              "python3-skimage:/usr/lib/python3/dist-packages/skimage/data/astronaut.png"
              "lomiri-wallpapers-20.04:/usr/share/backgrounds/Kleiber_by_Lukas_Baubkus.jpg")
  string(REPLACE ":" ";" photo "${photo}")
  list(GET photo 0 package)
  list(GET photo 1 file)
  if(NOT EXISTS "${file}")
    list(APPEND PINTAG_MISSING_TEST_PACKAGES "photographs for the synthetic scenes (${package})")
  endif()
endforeach()
