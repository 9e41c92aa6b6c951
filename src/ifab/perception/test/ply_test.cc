#include "ifab/perception/ply.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "ifab/core/error.h"

namespace ifab {
namespace {

PointCloud Sample() {
  PointCloud c;
  c.points = {{0.1, -2.5, 3.25}, {1e-3, 4.0, -0.5}, {7.125, 0.0, 1.0}};
  c.SetField("origin_x", {1.0, 1.5, 2.0});
  c.SetField("intensity", {10.0, 20.0, 30.0});
  return c;
}

void ExpectSame(const PointCloud& a, const PointCloud& b, double tol) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_LT((a.points[i] - b.points[i]).norm(), tol);
  ASSERT_EQ(a.fields.size(), b.fields.size());
  for (std::size_t f = 0; f < a.fields.size(); ++f) {
    EXPECT_EQ(a.fields[f].name, b.fields[f].name);
    for (std::size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a.fields[f].values[i], b.fields[f].values[i], tol);
  }
}

TEST(Ply, RoundTripsEveryFormatAndPrecision) {
  for (auto format : {PlyFormat::kAscii, PlyFormat::kBinaryLittleEndian, PlyFormat::kBinaryBigEndian}) {
    for (bool dbl : {false, true}) {
      std::stringstream s;
      WritePly(s, Sample(), {format, dbl, "test cloud"});
      ExpectSame(ReadPly(s, "mem.ply"), Sample(), dbl ? 1e-15 : 1e-6);
    }
  }
}

TEST(Ply, WritesAndReadsFiles) {
  const std::string path = (std::filesystem::temp_directory_path() / "ifab_ply_test.ply").string();
  {
    std::ofstream out(path, std::ios::binary);
    WritePly(out, Sample());
  }
  ExpectSame(ReadPly(path), Sample(), 1e-6);
  std::filesystem::remove(path);
}

TEST(Ply, ReadsMeshesFromOtherToolsAndSkipsWhatItDoesNotNeed) {
  // A MeshLab-style ASCII mesh: colours, normals and a face list after the vertices, CRLF lines.
  const std::string text =
      "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\nobj_info x\r\nelement vertex 3\r\n"
      "property double x\r\nproperty double y\r\nproperty double z\r\nproperty float nx\r\n"
      "property uchar red\r\nelement face 1\r\nproperty list uchar int vertex_indices\r\nend_header\r\n"
      "0 0 0 1 255\r\n1 0 0 0 128\r\n0 1 0 0 0\r\n3 0 1 2\r\n";
  std::istringstream in(text);
  const PointCloud c = ReadPly(in, "mesh.ply");
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c.points[1], Eigen::Vector3d(1, 0, 0));
  ASSERT_NE(c.Find("red"), nullptr);
  EXPECT_EQ((*c.Find("red"))[1], 128.0);

  // Binary with an element before the vertices that has a list (skipped byte by byte).
  std::string bin = "ply\nformat binary_little_endian 1.0\nelement camera 1\nproperty list uchar float k\n"
                    "element vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  const unsigned char count = 2;
  bin.push_back(static_cast<char>(count));
  const float k[2] = {1.0f, 2.0f}, xyz[3] = {0.5f, -1.0f, 2.0f};
  bin.append(reinterpret_cast<const char*>(k), sizeof(k));
  bin.append(reinterpret_cast<const char*>(xyz), sizeof(xyz));
  std::istringstream bin_in(bin);
  const PointCloud b = ReadPly(bin_in, "camera.ply");
  ASSERT_EQ(b.size(), 1u);
  EXPECT_EQ(b.points[0], Eigen::Vector3d(0.5, -1.0, 2.0));
}

void ExpectError(const std::string& text, const std::string& needle) {
  std::istringstream in(text);
  try {
    ReadPly(in, "bad.ply");
    ADD_FAILURE() << "no error for: " << text;
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("bad.ply"), std::string::npos) << msg;
    EXPECT_NE(msg.find(needle), std::string::npos) << "expected '" << needle << "' in: " << msg;
  }
}

TEST(Ply, BadFilesGiveAClearError) {
  const std::string head = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n";
  ExpectError("", "not a PLY file");
  ExpectError("PLY\nformat ascii 1.0\n", "not a PLY file");
  ExpectError("ply\nformat binary_middle_endian 1.0\nend_header\n", "unknown format 'binary_middle_endian'");
  ExpectError("ply\nelement vertex 1\nproperty float x\n", "no 'end_header'");
  ExpectError("ply\nelement vertex 0\nend_header\n", "no 'format'");
  ExpectError("ply\nformat ascii 1.0\nelement vertex -3\nend_header\n", "count >= 0");
  ExpectError("ply\nformat ascii 1.0\nelement vertex 1\nproperty quaternion x\nend_header\n", "unknown property type 'quaternion'");
  ExpectError("ply\nformat ascii 1.0\nproperty float x\nend_header\n", "property before any element");
  ExpectError("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n",
              "needs scalar properties x, y and z");
  ExpectError("ply\nformat ascii 1.0\nelement face 0\nend_header\n", "no 'vertex' element");
  ExpectError(head + "end_header\n1 2 3\n", "declares 2 vertices, the data ends at vertex 1");
  ExpectError(head + "end_header\n1 2 3\n4 five 6\n", "'five' is not a number (vertex 1, property y)");
  ExpectError(head + "bogus line\nend_header\n", "line 7: unexpected header line 'bogus line'");
  ExpectError("ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty double x\nproperty double y\n"
              "property double z\nend_header\n" + std::string(30, '\0'),
              "the data ends at vertex 1");
  try {
    ReadPly("/nonexistent/cloud.ply");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/cloud.ply: cannot open"), std::string::npos);
  }
}

TEST(Ply, RayPointsTravelAsOriginFields) {
  std::vector<RayPoint> rays{{{1, 2, 3}, {0, 0, 1.5}}, {{-1, 0, 0.5}, {0.1, 0, 1.4}}};
  std::stringstream s;
  WritePly(s, ToPointCloud(rays), {PlyFormat::kBinaryLittleEndian, true, ""});
  const auto back = ToRayPoints(ReadPly(s, "rays.ply"), "rays.ply");
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[1].origin, Eigen::Vector3d(0.1, 0, 1.4));
  PointCloud bare;
  bare.points = {{1, 2, 3}};
  EXPECT_THROW(ToRayPoints(bare, "bare.ply"), InputError);
  const Eigen::Vector3d o(0, 0, 2);
  EXPECT_EQ(ToRayPoints(bare, "bare.ply", &o)[0].origin, o);
}

}  // namespace
}  // namespace ifab
