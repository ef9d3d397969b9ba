// Stand-ins for the XR Hands package names (com.unity.xr.hands, assembly Unity.XR.Hands) that
// samples/unity/HandsimHands.cs uses, written from its public API reference: Handedness (Invalid 0, Left 1, Right 2:
// the enum that clashed with handsim's old Handedness), XRHandJointID with its values (Wrist 1, Palm 2, ThumbMetacarpal
// 3 ... LittleTip 26), XRHand, XRHandJoint and XRHandSubsystem. Compile-time only, like UnityEngine.cs.
using UnityEngine;

namespace UnityEngine.XR.Hands
{
    public enum Handedness { Invalid = 0, Left = 1, Right = 2 }

    public enum XRHandJointID
    {
        Invalid = 0, BeginMarker = 1, Wrist = 1, Palm = 2,
        ThumbMetacarpal = 3, ThumbProximal = 4, ThumbDistal = 5, ThumbTip = 6,
        IndexMetacarpal = 7, IndexProximal = 8, IndexIntermediate = 9, IndexDistal = 10, IndexTip = 11,
        MiddleMetacarpal = 12, MiddleProximal = 13, MiddleIntermediate = 14, MiddleDistal = 15, MiddleTip = 16,
        RingMetacarpal = 17, RingProximal = 18, RingIntermediate = 19, RingDistal = 20, RingTip = 21,
        LittleMetacarpal = 22, LittleProximal = 23, LittleIntermediate = 24, LittleDistal = 25, LittleTip = 26,
        EndMarker = 27
    }

    public struct XRHandJoint
    {
        public XRHandJointID id { get { return XRHandJointID.Invalid; } }
        public Handedness handedness { get { return Handedness.Invalid; } }
        public bool TryGetPose(out Pose pose) { pose = Pose.identity; return false; }
        public bool TryGetRadius(out float radius) { radius = 0; return false; }
    }

    public struct XRHand
    {
        public Handedness handedness { get { return Handedness.Invalid; } }
        public bool isTracked { get { return false; } }
        public Pose rootPose { get { return Pose.identity; } }
        public XRHandJoint GetJoint(XRHandJointID id) { return default(XRHandJoint); }
    }

    public class XRHandSubsystem : ISubsystem
    {
        public bool running { get { return false; } }
        public XRHand leftHand { get { return default(XRHand); } }
        public XRHand rightHand { get { return default(XRHand); } }
    }
}
