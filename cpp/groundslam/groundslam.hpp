#pragma once
// groundslam's public interface in one header: configuration, the SLAM pipeline, datasets and the runner that
// feeds them to it, trajectories and their evaluation, maps, vocabularies and the simulator.
// Link groundslam::groundslam (CMake: find_package(groundslam REQUIRED)).

#include "groundslam/eval/TrajectoryMetrics.hpp"
#include "groundslam/io/ConfigNames.hpp"
#include "groundslam/io/ConfigYaml.hpp"
#include "groundslam/io/DataFiles.hpp"
#include "groundslam/io/Dataset.hpp"
#include "groundslam/io/DatasetRunner.hpp"
#include "groundslam/io/ImageFile.hpp"
#include "groundslam/io/InputError.hpp"
#include "groundslam/io/MapFile.hpp"
#include "groundslam/io/Tum.hpp"
#include "groundslam/io/VocabularyFile.hpp"
#include "groundslam/pipeline/Config.hpp"
#include "groundslam/pipeline/FrameResult.hpp"
#include "groundslam/pipeline/PipelinedSlam.hpp"
#include "groundslam/pipeline/Slam.hpp"
#include "groundslam/sim/Simulator.hpp"
