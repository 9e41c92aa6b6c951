// Fixture for the layering check: an algorithm module that writes a file of its own (the check
// must fail on it; algorithm modules write no files). Not compiled.
#include <fstream>

void SaveMissionLog() {
  std::ofstream out("mission.log");
  out << "placed\n";
}
