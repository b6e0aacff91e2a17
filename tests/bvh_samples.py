"""Tiny hand-written BVH texts shared by the mocap tests."""

TWO_JOINT = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation
  JOINT Chest
  {
    OFFSET 0 2 0
    CHANNELS 3 Zrotation Yrotation Xrotation
    End Site
    {
      OFFSET 0 1 0
    }
  }
  JOINT LeftLeg
  {
    OFFSET 1 -1 0
    CHANNELS 3 Xrotation Yrotation Zrotation
    End Site
    {
      OFFSET 0 -3 0
    }
  }
  JOINT RightLeg
  {
    OFFSET -1 -1 0
    CHANNELS 3 Xrotation Yrotation Zrotation
    End Site
    {
      OFFSET 0 -3 0
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.033333
0 10 0 0 0 0 0 0 0 0 0 0 0 0 0
1 10 0 90 0 0 0 0 0 45 0 0 -45 0 0
2 10 0 0 90 0 30 0 0 0 0 90 0 0 0
"""
