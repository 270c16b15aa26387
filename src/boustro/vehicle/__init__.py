"""The vehicle: turn radius, Dubins and Reeds-Shepp turns, the turns between lanes."""

from .curves import Word, arc_step, end_pose, sample_word
from .dubins import DUBINS_WORDS, dubins_length, dubins_path, dubins_paths, dubins_words
from .model import Vehicle
from .reeds_shepp import reeds_shepp_length, reeds_shepp_path, reeds_shepp_paths, reeds_shepp_words
from .turns import (
    Turn,
    every_turn,
    lane_order,
    pose_length,
    skip_order,
    turn_between,
    turn_length,
    turns_between,
)

__all__ = [
    "DUBINS_WORDS",
    "Turn",
    "Vehicle",
    "Word",
    "arc_step",
    "dubins_length",
    "dubins_path",
    "dubins_paths",
    "dubins_words",
    "end_pose",
    "every_turn",
    "lane_order",
    "pose_length",
    "reeds_shepp_length",
    "reeds_shepp_path",
    "reeds_shepp_paths",
    "reeds_shepp_words",
    "sample_word",
    "skip_order",
    "turn_between",
    "turn_length",
    "turns_between",
]
