// A fixture of tests/docs: the coordinator's declaration as src/robot/layering.cpp writes it.
namespace fixture {
const auto coordinator = make("behavior_coordinator", true, "fuses the commands of the active behaviors", {"behavior_command*"},
                              {"cmd_vel"}, where);
class RealType {};
bool keys = r.expect_keys(root, {"robot", "behaviors"}, "the robot profile");
}  // namespace fixture
