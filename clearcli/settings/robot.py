"""Robot settings (section [robot]): which arm, where it stands and how IK is searched.
The defaults are the WAM's (the default profile); another profile (``name``) supplies its
own for [robot] and [gripper] (clearcli/settings/profiles.py), which a user's values
override."""

from __future__ import annotations

from dataclasses import dataclass

from clearcli.settings.fields import Section, param, range_of
from clearcli.settings.profiles import DEFAULT_PROFILE, PROFILE_NAMES


@dataclass(frozen=True)
class RobotSettings(Section):
    NAME = "robot"

    # the robot profile: arm, gripper, IK (`clear robots` lists them; their registry:
    # clearcli/settings/profiles.py)
    name: str = param(DEFAULT_PROFILE, choices=PROFILE_NAMES)
    # Your own arm: its URDF ("" = the profile's description). Any serial chain of 6 or
    # more revolute joints up to flange_frame (other joints, a gripper's fingers, are held
    # at 0); the profile named above still supplies the [robot] and [gripper] defaults.
    urdf: str = param("", text='"" or a URDF file')
    # its base frame ("" = the URDF's root link) and flange ("" = the end of its longest chain)
    base_frame: str = param("", text='"" or a frame of the URDF')
    flange_frame: str = param("", text='"" or a frame of the URDF')
    # the gripper's closing point in the flange frame (m; () = on the flange), and the turn
    # about the flange's z that makes x the fingers' closing direction (degrees)
    tcp_xyz_m: tuple[float, ...] = param((), ge=-0.5, le=0.5, lengths=(0, 3))
    tcp_yaw_deg: float = param(0.0, ge=-180, le=180)
    # T_base_camera as x y z qx qy qz qw of the points' frame in the WAM base frame;
    # empty = derive from the table (see clearcli/robot/placement.py).
    camera_pose: tuple[float, ...] = param((), ge=-100, le=100, lengths=(0, 7))
    ik_seeds: int = param(8, ge=1, le=200)
    ik_tolerance_m: float = param(0.001, gt=0, le=0.1)
    ik_tolerance_rad: float = param(0.01, gt=0, le=1)
    # Damped least squares: 0.05 keeps steps bounded near singularities (the straight-up
    # home pose) while still converging in ~20 iterations far from them.
    ik_damping: float = param(0.05, gt=0, le=10)
    ik_max_iterations: int = param(150, ge=1, le=10000)
    # The default placement puts the WAM footprint this far outside the table edge
    # nearest the camera: about the radius of the WAM base, so the base clears the table.
    base_outside_edge_m: float = param(0.10, ge=0, le=2)
    # ...and at least this far (on the table plane) from every object's centroid: the
    # visible table edge can be a crop with objects right at it, and a WAM cannot reach
    # down beside its own base (top grasps fail there in IK).
    base_min_object_distance_m: float = param(0.30, ge=0, le=2)
    # ...and farther back, up to this from the nearest object, while the farthest stays
    # within base_max_object_distance_m: a push towards the base starts 5-15 cm nearer
    # than its object, and top-down poses with the wrist centre within ~0.26 m of the
    # shoulder axis have no IK (measured on the simulated sessions' failures).
    base_preferred_object_distance_m: float = param(0.40, ge=0, le=2)
    # the WAM's tool plate reaches 0.915 m from the shoulder; top grasps of tall objects
    # need some of it
    base_max_object_distance_m: float = param(0.85, gt=0, le=2)
    # Arm links must keep this clearance from the table plane and from other objects'
    # hulls (the gripper itself is checked by the predicates: block_grasp, block_dir).
    collision_margin_m: float = param(0.01, ge=0, le=0.2)

    def cross_checks(self) -> None:
        if self.tcp_xyz_m and sum(v * v for v in self.tcp_xyz_m) > 0.25:
            self.fail("tcp_xyz_m", "the tool-centre offset must be within 0.5 m of the flange")
        if not self.urdf:
            for key in ("base_frame", "flange_frame", "tcp_xyz_m", "tcp_yaw_deg"):
                if getattr(self, key):
                    self.fail(
                        key,
                        f"accepted: {range_of(type(self), key).describe()}, with [robot] urdf: it describes "
                        "your own URDF; give urdf too",
                    )
        if self.camera_pose and sum(v * v for v in self.camera_pose[3:]) < 1e-6:
            self.fail("camera_pose", "its quaternion (the last four numbers) must not be zero")
        if self.base_max_object_distance_m < self.base_min_object_distance_m:
            self.fail(
                "base_max_object_distance_m",
                f"must be at least base_min_object_distance_m ({self.base_min_object_distance_m:g})",
            )
