// input_silence_s in the three process configs: the shipped YAMLs hold the code's default,
// the loaders read a value (0 = off) and refuse bad ones naming the key.

#include <string>

#include <gtest/gtest.h>

#include "daemon/capture/capture_config.h"
#include "daemon/common/input_silence.h"
#include "daemon/common/yaml_config.h"
#include "daemon/mapper/mapper_config_loader.h"
#include "daemon/tracker/tracker_config.h"

namespace cblox {
namespace {

std::string config(const char* name) { return std::string(CBLOX_CONFIG_DIR) + "/" + name; }

TEST(InputSilenceConfigTest, ShippedYamlsHoldTheCodeDefault) {
  EXPECT_EQ(kDefaultInputSilenceS, 2.0);
  const CaptureConfig capture;
  const TrackerProcessConfig tracker;
  const MapperProcessConfig mapper;
  EXPECT_EQ(capture.input_silence_s, kDefaultInputSilenceS);
  EXPECT_EQ(tracker.input_silence_s, kDefaultInputSilenceS);
  EXPECT_EQ(mapper.input_silence_s, kDefaultInputSilenceS);
  EXPECT_EQ(loadCaptureConfig(loadYamlFile(config("capture.yaml"))).input_silence_s,
            kDefaultInputSilenceS);
  EXPECT_EQ(loadTrackerConfig(loadYamlFile(config("tracker.yaml"))).input_silence_s,
            kDefaultInputSilenceS);
  EXPECT_EQ(loadMapperConfig(loadYamlFile(config("mapper.yaml"))).input_silence_s,
            kDefaultInputSilenceS);
}

TEST(InputSilenceConfigTest, LoadersReadTheValue) {
  EXPECT_EQ(loadCaptureConfig(YAML::Load("input_silence_s: 5.5")).input_silence_s, 5.5);
  EXPECT_EQ(loadTrackerConfig(YAML::Load("input_silence_s: 0")).input_silence_s, 0.0);
  EXPECT_EQ(loadMapperConfig(YAML::Load("input_silence_s: 0.25")).input_silence_s, 0.25);
}

template <typename Load>
void expectRefused(Load load, const std::string& yaml) {
  try {
    load(YAML::Load(yaml));
    ADD_FAILURE() << "accepted: " << yaml;
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("input_silence_s"), std::string::npos) << e.what();
  }
}

TEST(InputSilenceConfigTest, BadValuesAreRefusedNamingTheKey) {
  for (const std::string yaml : {"input_silence_s: -1", "input_silence_s: .nan",
                                 "input_silence_s: .inf", "input_silence_s: soon"}) {
    expectRefused([](const YAML::Node& n) { return loadCaptureConfig(n); }, yaml);
    expectRefused([](const YAML::Node& n) { return loadTrackerConfig(n); }, yaml);
    expectRefused([](const YAML::Node& n) { return loadMapperConfig(n); }, yaml);
  }
}

}  // namespace
}  // namespace cblox
