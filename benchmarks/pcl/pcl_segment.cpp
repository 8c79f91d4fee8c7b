// PCL's tabletop pipeline, timed stage by stage, for the side-by-side benchmark of
// benchmarks/pcl.py: NaN removal, statistical outlier removal, RANSAC plane, convex hull
// of the plane and the polygonal prism above it, supervoxels, LCCP.
//
//     pcl_segment [--repeat R] FILE.pcd...
//
// One JSON line per frame and repeat on stdout: the seconds of each stage (the read
// included, as clear's figure is its read + segment), their total, the points at each
// step and the object count (LCCP segments of at least --min-points points).
// Supervoxel and LCCP parameters are those of PCL's LCCP example; lengths in metres,
// angles in degrees.

#include <pcl/ModelCoefficients.h>
#include <pcl/filters/filter.h>
#include <pcl/filters/project_inliers.h>
#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/segmentation/extract_polygonal_prism_data.h>
#include <pcl/segmentation/lccp_segmentation.h>
#include <pcl/segmentation/sac_segmentation.h>
#include <pcl/segmentation/supervoxel_clustering.h>
#include <pcl/surface/convex_hull.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

using Point = pcl::PointXYZRGBA;
using Cloud = pcl::PointCloud<Point>;

namespace {

struct Params {
  int repeat = 1;
  // statistical outlier removal: neighbours and the standard deviations kept (10
  // neighbours, not the tutorials' 50: the pass is most of PCL's time either way, and
  // the cheaper one keeps the comparison conservative)
  int sor_k = 10;
  double sor_stddev = 1.0;
  // RANSAC plane: inlier distance (m) and iterations
  double plane_distance_m = 0.01;
  int plane_iterations = 200;
  // prism above the table's hull: heights (m) along the normal toward the camera
  double prism_min_m = 0.005;
  double prism_max_m = 0.5;
  // supervoxels (PCL's LCCP example's defaults)
  float voxel_m = 0.0075f;
  float seed_m = 0.03f;
  float color_importance = 0.0f;
  float spatial_importance = 1.0f;
  float normal_importance = 4.0f;
  // LCCP
  float concavity_tolerance_deg = 10.0f;
  float smoothness_threshold = 0.1f;
  unsigned int k_factor = 1;  // 1: extended convexity (fewer false cuts), 0: plain
  unsigned int min_segment_supervoxels = 3;  // smaller segments merged into a neighbour
  // objects counted: LCCP segments with at least this many points
  std::size_t min_points = 300;
};

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point& t0) {
  const auto t1 = Clock::now();
  const double s = std::chrono::duration<double>(t1 - t0).count();
  t0 = t1;
  return s;
}

struct Stage {
  const char* name;
  double seconds;
};

// One frame through the pipeline; prints its JSON line. False when the file cannot be read.
bool run_frame(const std::string& path, const Params& p) {
  std::vector<Stage> stages;
  auto t = Clock::now();

  Cloud::Ptr raw(new Cloud);
  if (pcl::io::loadPCDFile<Point>(path, *raw) != 0) {
    std::fprintf(stderr, "pcl_segment: cannot read %s\n", path.c_str());
    return false;
  }
  stages.push_back({"read", seconds_since(t)});

  Cloud::Ptr finite(new Cloud);
  pcl::Indices kept;
  pcl::removeNaNFromPointCloud(*raw, *finite, kept);
  stages.push_back({"nan", seconds_since(t)});

  Cloud::Ptr clean(new Cloud);
  pcl::StatisticalOutlierRemoval<Point> sor;
  sor.setInputCloud(finite);
  sor.setMeanK(p.sor_k);
  sor.setStddevMulThresh(p.sor_stddev);
  sor.filter(*clean);
  stages.push_back({"outliers", seconds_since(t)});

  pcl::ModelCoefficients::Ptr plane(new pcl::ModelCoefficients);
  pcl::PointIndices::Ptr table(new pcl::PointIndices);
  pcl::SACSegmentation<Point> sac;
  sac.setOptimizeCoefficients(true);
  sac.setModelType(pcl::SACMODEL_PLANE);
  sac.setMethodType(pcl::SAC_RANSAC);
  sac.setDistanceThreshold(p.plane_distance_m);
  sac.setMaxIterations(p.plane_iterations);
  sac.setInputCloud(clean);
  sac.segment(*table, *plane);
  stages.push_back({"plane", seconds_since(t)});

  Cloud::Ptr above(new Cloud);
  if (table->indices.size() >= 3) {
    Cloud::Ptr on_plane(new Cloud);
    pcl::ProjectInliers<Point> project;
    project.setModelType(pcl::SACMODEL_PLANE);
    project.setInputCloud(clean);
    project.setIndices(table);
    project.setModelCoefficients(plane);
    project.filter(*on_plane);

    Cloud::Ptr hull(new Cloud);
    pcl::ConvexHull<Point> chull;
    chull.setDimension(2);
    chull.setInputCloud(on_plane);
    chull.reconstruct(*hull);

    pcl::PointIndices::Ptr inside(new pcl::PointIndices);
    pcl::ExtractPolygonalPrismData<Point> prism;
    prism.setInputCloud(clean);
    prism.setInputPlanarHull(hull);
    prism.setHeightLimits(p.prism_min_m, p.prism_max_m);
    prism.segment(*inside);
    above->reserve(inside->indices.size());
    for (const auto i : inside->indices) above->push_back((*clean)[i]);
  }
  stages.push_back({"hull_prism", seconds_since(t)});

  std::size_t supervoxel_count = 0;
  std::size_t objects = 0;
  if (!above->empty()) {
    pcl::SupervoxelClustering<Point> super(p.voxel_m, p.seed_m);
    super.setUseSingleCameraTransform(true);  // a camera frame: the octree's depth transform
    super.setInputCloud(above);
    super.setColorImportance(p.color_importance);
    super.setSpatialImportance(p.spatial_importance);
    super.setNormalImportance(p.normal_importance);
    std::map<std::uint32_t, pcl::Supervoxel<Point>::Ptr> clusters;
    super.extract(clusters);
    std::multimap<std::uint32_t, std::uint32_t> adjacency;
    super.getSupervoxelAdjacency(adjacency);
    supervoxel_count = clusters.size();
    stages.push_back({"supervoxels", seconds_since(t)});

    pcl::LCCPSegmentation<Point> lccp;
    lccp.setConcavityToleranceThreshold(p.concavity_tolerance_deg);
    lccp.setSanityCheck(true);
    lccp.setSmoothnessCheck(true, p.voxel_m, p.seed_m, p.smoothness_threshold);
    lccp.setKFactor(p.k_factor);
    lccp.setMinSegmentSize(p.min_segment_supervoxels);
    lccp.setInputSupervoxels(clusters, adjacency);
    lccp.segment();
    pcl::PointCloud<pcl::PointXYZL>::Ptr labelled = super.getLabeledCloud();
    lccp.relabelCloud(*labelled);
    std::unordered_map<std::uint32_t, std::size_t> sizes;
    for (const auto& q : labelled->points)
      if (q.label != 0) ++sizes[q.label];
    for (const auto& [label, n] : sizes)
      if (n >= p.min_points) ++objects;
    stages.push_back({"lccp", seconds_since(t)});
  } else {
    stages.push_back({"supervoxels", 0.0});
    stages.push_back({"lccp", seconds_since(t)});
  }

  double total = 0.0;
  std::printf("{\"frame\": \"%s\", \"points\": %zu, \"finite\": %zu, \"clean\": %zu, \"table\": %zu, "
              "\"above\": %zu, \"supervoxels\": %zu, \"objects\": %zu, \"stages_s\": {",
              path.c_str(), raw->size(), finite->size(), clean->size(), table->indices.size(), above->size(),
              supervoxel_count, objects);
  for (std::size_t i = 0; i < stages.size(); ++i) {
    std::printf("%s\"%s\": %.6f", i ? ", " : "", stages[i].name, stages[i].seconds);
    total += stages[i].seconds;
  }
  std::printf("}, \"total_s\": %.6f}\n", total);
  std::fflush(stdout);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Params p;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--repeat" && i + 1 < argc) {
      p.repeat = std::max(1, std::atoi(argv[++i]));
    } else if (arg == "--min-points" && i + 1 < argc) {
      p.min_points = static_cast<std::size_t>(std::atol(argv[++i]));
    } else if (arg == "--sor-k" && i + 1 < argc) {
      p.sor_k = std::atoi(argv[++i]);
    } else if (arg == "--k-factor" && i + 1 < argc) {
      p.k_factor = static_cast<unsigned int>(std::atoi(argv[++i]));
    } else if (arg == "--min-segment" && i + 1 < argc) {
      p.min_segment_supervoxels = static_cast<unsigned int>(std::atoi(argv[++i]));
    } else if (arg == "--help" || arg == "-h") {
      std::printf("usage: pcl_segment [--repeat R] [--min-points N] [--sor-k K] [--k-factor 0|1] [--min-segment S] FILE.pcd...\n");
      return 0;
    } else {
      files.push_back(arg);
    }
  }
  if (files.empty()) {
    std::fprintf(stderr, "usage: pcl_segment [--repeat R] [--min-points N] [--sor-k K] [--k-factor 0|1] [--min-segment S] FILE.pcd...\n");
    return 2;
  }
  pcl::console::setVerbosityLevel(pcl::console::L_ERROR);
  int failed = 0;
  for (const auto& f : files)
    for (int r = 0; r < p.repeat; ++r)
      if (!run_frame(f, p)) {
        ++failed;
        break;
      }
  return failed ? 1 : 0;
}
