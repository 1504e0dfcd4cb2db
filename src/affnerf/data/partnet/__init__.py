"""PartNet-Mobility import: URDF kinematics, part hierarchy, affordance mapping and OBJ loading (conventions §3).

The entry point is :func:`load_partnet_object`, which turns an object folder into an
:class:`~affnerf.objects.asset.ObjectAsset`; :func:`write_partnet_fixture` writes a tiny object in the same format
for tests.
"""

from affnerf.data.partnet.fixture import write_partnet_fixture
from affnerf.data.partnet.hierarchy import Leaf, read_leaves, read_model_cat
from affnerf.data.partnet.kinematics import JOINT_STATE_MODES, joint_values, link_poses
from affnerf.data.partnet.loader import load_partnet_object
from affnerf.data.partnet.mapping import CategoryMapping, leaf_affordance, load_mapping
from affnerf.data.partnet.objfile import ObjMesh, read_obj
from affnerf.data.partnet.urdf import Joint, Link, Urdf, Visual, parse_urdf

__all__ = [
    "JOINT_STATE_MODES",
    "CategoryMapping",
    "Joint",
    "Leaf",
    "Link",
    "ObjMesh",
    "Urdf",
    "Visual",
    "joint_values",
    "leaf_affordance",
    "link_poses",
    "load_mapping",
    "load_partnet_object",
    "parse_urdf",
    "read_leaves",
    "read_model_cat",
    "read_obj",
    "write_partnet_fixture",
]
