// Unity sample. The plugin bundle (make plugin) ships it in its Unity package (Samples~/Hands, with Handsim.cs and
// the native plugin under Runtime/); docs/native.md has the steps. It has not been run in Unity: ctest
// unity_sample_compiles compiles it with mcs against stand-ins of the UnityEngine and XR Hands names it uses
// (tests/unity/), which catches clashes such as XR Hands' Handedness against ours (hence HandSide).
//
// What it does each frame: reads each hand's 26 joints, either from XR Hands (XRHandSubsystem) or from 26 joint
// Transforms (OpenXR order; any rig), converts them from Unity space to handsim space, steps the world, and writes
// the simulated poses back onto the bound Transforms and the skinned hand meshes. Every conversion and all the
// handsim logic live in Handsim.cs (compiled and tested under Mono by ctest csharp_abi, which also checks that
// such a frame loop allocates nothing); this file only moves data between Unity objects and those calls, into
// arrays allocated once.
using System.Collections.Generic;
using Handsim;
using UnityEngine;
using UnityEngine.XR.Hands;

public class HandsimHands : MonoBehaviour
{
    [System.Serializable]
    public class TrackedJoints
    {
        public HandSide handedness = HandSide.Right;
        [Tooltip("Read this hand from XR Hands' running XRHandSubsystem (its leftHand / rightHand) instead of joints.")]
        public bool fromXRHands = true;
        [Tooltip("26 joints in OpenXR order (palm, wrist, thumb metacarpal ... little tip). With XR Hands, joint i is " +
                 "XRHandJointID value UnityConvert.XRHandJointID(i).")]
        public Transform[] joints = new Transform[Native.HandJointCount];
        [Tooltip("Optional: shows the simulated hand (deformed around objects instead of passing through them).")]
        public MeshFilter renderMesh;
    }

    [System.Serializable]
    public class BoxBody
    {
        public Transform target;         // its BoxCollider (if any) gives the size, else its lossy scale
        public float mass = 0.2f;        // 0: static
    }

    public TrackedJoints[] hands = { new TrackedJoints() };
    public BoxBody[] boxes = new BoxBody[0];
    [Tooltip("Recompute the hand meshes' normals every frame (a pass over all 39k vertices; off: the normals of the " +
             "first frame stay, which is enough for a flat or unlit material).")]
    public bool recalculateNormals = false;
    [Tooltip("Add the paper's jewelry box and drive these Transforms with its base and lid.")]
    public bool jewelryBox = true;
    public Transform jewelryBase, jewelryLid;

    World world;
    TrackedHand[] input;
    HandId[] handIds;
    readonly List<KeyValuePair<BodyId, Transform>> bound = new List<KeyValuePair<BodyId, Transform>>();
    BodyId[] boundIds = new BodyId[0];
    Handsim.Pose[] boundPoses = new Handsim.Pose[0];
    readonly float[] positions = new float[3 * Native.HandJointCount];
    readonly float[] rotations = new float[4 * Native.HandJointCount];
    readonly bool[] valid = new bool[Native.HandJointCount];
    readonly float[] radii = new float[Native.HandJointCount];
    float[] vertices;
    Vector3[][] unityVertices;  // per hand, allocated once
    Handsim.Event[] events;  // UnityEngine has its own Event, Pose and EventType: qualify
    bool[] normalsDone = new bool[0];
    XRHandSubsystem xrHands;
    readonly List<XRHandSubsystem> subsystems = new List<XRHandSubsystem>();

    void Start()
    {
        world = new World();  // checks the plugin's ABI version, throws HandsimException on a mismatch
        input = new TrackedHand[hands.Length];
        handIds = new HandId[hands.Length];
        unityVertices = new Vector3[hands.Length][];
        normalsDone = new bool[hands.Length];
        for (int h = 0; h < hands.Length; ++h)
        {
            HandDef def = HandDef.Default;
            def.Handedness = hands[h].handedness;
            handIds[h] = world.AddHand(def);
            input[h] = new TrackedHand(handIds[h], hands[h].handedness);
            if (hands[h].renderMesh != null)
            {
                var mesh = new Mesh { indexFormat = UnityEngine.Rendering.IndexFormat.UInt32 };
                unityVertices[h] = new Vector3[world.HandInfo(handIds[h]).VertexCount];
                mesh.vertices = unityVertices[h];
                mesh.triangles = UnityConvert.TrianglesToUnity(world.HandTriangles(handIds[h]));
                hands[h].renderMesh.mesh = mesh;
            }
        }
        foreach (BoxBody b in boxes)
        {
            BodyDef def = BodyDef.Default;
            Vector3 half = 0.5f * Vector3.Scale(b.target.lossyScale, b.target.TryGetComponent(out BoxCollider c) ? c.size : Vector3.one);
            def.Shape = Shape.Box(half.x, half.y, half.z);
            def.Mass = b.mass;
            def.Pose = FromUnity(b.target);
            Bind(world.AddBody(def), b.target);
        }
        if (jewelryBox)
        {
            JewelryBox box = world.BuildJewelryBox();
            Bind(box.Base, jewelryBase);
            Bind(box.Lid, jewelryLid);
        }
    }

    void Bind(BodyId id, Transform target)
    {
        if (target == null) return;
        bound.Add(new KeyValuePair<BodyId, Transform>(id, target));
        boundIds = new BodyId[bound.Count];
        boundPoses = new Handsim.Pose[bound.Count];
        for (int i = 0; i < bound.Count; ++i) boundIds[i] = bound[i].Key;
    }

    static Handsim.Pose FromUnity(Transform t)
    {
        Vector3 p = t.position;
        Quaternion q = t.rotation;
        return new Handsim.Pose(UnityConvert.PositionFromUnity(p.x, p.y, p.z), UnityConvert.RotationFromUnity(q.x, q.y, q.z, q.w));
    }

    void Update()
    {
        // Hand input: Unity space -> handsim space. An untracked joint (XR Hands) or a missing or inactive joint
        // Transform is an invalid joint; a hand whose palm or wrist is invalid is untracked this frame (the world
        // releases what it held after its grace time).
        for (int h = 0; h < hands.Length; ++h)
        {
            if (hands[h].fromXRHands) ReadXRHand(hands[h].handedness);
            else ReadTransforms(hands[h].joints);
            UnityConvert.JointsFromUnity(positions, rotations, hands[h].fromXRHands ? radii : null, valid, input[h].Joints);
        }

        world.StepHands(Time.deltaTime, input);  // fixed substeps inside: frame-rate independent

        // Simulated poses -> Transforms, in one native call.
        if (boundIds.Length > 0)
        {
            world.BodyPoses(boundIds, boundPoses);
            for (int i = 0; i < boundIds.Length; ++i)
            {
                float px, py, pz, qx, qy, qz, qw;
                UnityConvert.ToUnity(boundPoses[i].Position, out px, out py, out pz);
                UnityConvert.ToUnity(boundPoses[i].Orientation, out qx, out qy, out qz, out qw);
                bound[i].Value.SetPositionAndRotation(new Vector3(px, py, pz), new Quaternion(qx, qy, qz, qw));
            }
        }

        // Deformed hand meshes (world space: put the MeshFilter's GameObject at the origin, unrotated).
        for (int h = 0; h < hands.Length; ++h)
        {
            if (hands[h].renderMesh == null) continue;
            int n = world.HandRenderVerticesF32(handIds[h], ref vertices);
            UnityConvert.VerticesToUnity(vertices, n);
            Vector3[] v = unityVertices[h];
            for (int i = 0; i < n; ++i) v[i] = new Vector3(vertices[3 * i], vertices[3 * i + 1], vertices[3 * i + 2]);
            Mesh mesh = hands[h].renderMesh.mesh;
            mesh.vertices = v;
            if (recalculateNormals || !normalsDone[h]) { mesh.RecalculateNormals(); normalsDone[h] = true; }
            mesh.RecalculateBounds();
        }

        // Events are pulled, not called back.
        int count = world.Events(ref events);
        for (int i = 0; i < count; ++i)
            if (events[i].Type == Handsim.EventType.GraspBegin || events[i].Type == Handsim.EventType.GraspEnd)
                Debug.Log("handsim: " + events[i]);
    }

    // One XR Hands hand into positions/rotations/radii/valid (session space, which is the XR Origin's: put this
    // component's world at the origin, or convert the poses with the XR Origin's transform first).
    void ReadXRHand(HandSide side)
    {
        if (xrHands == null || !xrHands.running)
        {
            SubsystemManager.GetSubsystems(subsystems);
            xrHands = null;
            foreach (XRHandSubsystem s in subsystems) if (s.running) { xrHands = s; break; }
        }
        bool tracked = false;
        XRHand hand = default(XRHand);
        if (xrHands != null)
        {
            hand = side == HandSide.Left ? xrHands.leftHand : xrHands.rightHand;
            tracked = hand.isTracked && hand.handedness == (side == HandSide.Left ? Handedness.Left : Handedness.Right);
        }
        for (int j = 0; j < Native.HandJointCount; ++j)
        {
            UnityEngine.Pose pose = UnityEngine.Pose.identity;
            float radius = 0.01f;
            valid[j] = tracked && hand.GetJoint((XRHandJointID)UnityConvert.XRHandJointID(j)).TryGetPose(out pose);
            if (valid[j] && !hand.GetJoint((XRHandJointID)UnityConvert.XRHandJointID(j)).TryGetRadius(out radius))
                radius = 0.01f;  // the provider gives no radius: 1 cm, a finger joint's order of size
            Store(j, pose.position, pose.rotation);
            radii[j] = radius;
        }
    }

    void ReadTransforms(Transform[] joints)
    {
        for (int j = 0; j < Native.HandJointCount; ++j)
        {
            Transform t = j < joints.Length ? joints[j] : null;
            valid[j] = t != null && t.gameObject.activeInHierarchy;
            Store(j, valid[j] ? t.position : Vector3.zero, valid[j] ? t.rotation : Quaternion.identity);
        }
    }

    void Store(int j, Vector3 p, Quaternion q)
    {
        positions[3 * j] = p.x; positions[3 * j + 1] = p.y; positions[3 * j + 2] = p.z;
        rotations[4 * j] = q.x; rotations[4 * j + 1] = q.y; rotations[4 * j + 2] = q.z; rotations[4 * j + 3] = q.w;
    }

    void OnDestroy()
    {
        if (world != null) world.Dispose();
    }
}
