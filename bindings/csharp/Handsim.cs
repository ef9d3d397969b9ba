// handsim for C#: P/Invoke declarations of libhandsim (bindings/c/handsim.h) and a small idiomatic layer on top.
//
//  - Handsim.Native: the C functions one to one (cdecl, int status), for hosts that manage buffers themselves.
//  - Structs with [StructLayout(Sequential)] that match the C structs field for field; the csharp_abi test checks
//    Marshal.SizeOf / OffsetOf of every one against the layout table the library reports (handsim_layout).
//  - Handsim.World: owns the native world through a SafeHandle (Dispose, or the finalizer, destroys it) and turns
//    every non-zero status into a HandsimException carrying the status and the native message.
//  - Handsim.UnityConvert: handsim is right-handed Y-up, Unity left-handed Y-up; conversions live here, not in
//    the core. Nothing in this file references UnityEngine, so it compiles with plain mcs/csc.
//
// Units: metres, seconds, radians; quaternions x, y, z, w. The library is loaded as "handsim" (libhandsim.so,
// handsim.dll, libhandsim.dylib); see docs/native.md for Unity and other engines.
using System;
using System.Runtime.InteropServices;

namespace Handsim
{
    // --- statuses and enums (the numbers of handsim.h) ---------------------------------------------------------
    // Each is one enum of the core's table (core/include/handsim/enum_table.h); the csharp_abi test walks the
    // library's rows (handsim_enum_value) and fails on a value missing here, named differently or numbered apart.

    public enum Status { Ok = 0, InvalidArgument = 1, StaleId = 2, InvalidState = 3, Unsupported = 4, Internal = 5 }
    public enum ShapeType { Box = 0, Sphere = 1, Capsule = 2, ConvexHull = 3, TriangleMesh = 4 }
    public enum BodyMotion { Static = 0, Dynamic = 1, Kinematic = 2 }
    public enum JointType { Hinge = 0, Slider = 1, Ball = 2, Fixed = 3 }
    public enum JointSolver { Exact = 0, Lm = 1, LmCeres = 2 }
    public enum JointModel { Hard = 0, Soft = 1 }
    public enum JointTermination { Converged = 0, MaxIterations = 1, Degenerate = 2, AtLimit = 3 }
    // Not "Handedness": UnityEngine.XR.Hands has a Handedness enum (Invalid 0, Left 1, Right 2), and a script using both
    // namespaces would not compile (CS0104). The values are the C ABI's HANDSIM_LEFT / HANDSIM_RIGHT.
    public enum HandSide { Left = 0, Right = 1 }
    public enum ParticleSampling { Random = 0, Even = 1 }
    public enum ParticleContacts { ClosedForm = 0, BulletObjects = 1 }
    public enum PushModel { Fit = 0, Physical = 1, Wrap = 2 }
    public enum EventType { ContactBegin = 0, ContactEnd = 1, GraspBegin = 2, GraspEnd = 3 }
    public enum EventReason { None = 0, Released = 1, TrackingLost = 2, BodyRemoved = 3, HandRemoved = 4 }
    public enum Stage { Skinning = 0, Contacts = 1, Deformation = 2, Grasp = 3, Attach = 4, PoseFit = 5, Dynamics = 6,
                        Joints = 7, Slip = 8 }
    public enum SkipReason { None = 0, NoTrackedHand = 1, NoHandNearBody = 2, NoParticleInside = 3, NoMovableBodyTouched = 4,
                             NothingGrasped = 5, NoFreeBodyTouched = 6, BelowSubstep = 7, NoJoints = 8, NoSecondHand = 9 }
    public enum StepWarning { SubstepsDropped = 0, NonFiniteRecovered = 1, HandTeleported = 2 }  // bit indices of StepReport.Warnings

    /// <summary>A failed native call: the status and the library's message (which names the argument).</summary>
    public sealed class HandsimException : Exception
    {
        public Status Status { get; private set; }
        public string NativeMessage { get; private set; }

        public HandsimException(Status status, string nativeMessage, string call)
            : base(call + ": " + status + ": " + nativeMessage)
        {
            Status = status;
            NativeMessage = nativeMessage;
        }
    }

    // --- blittable value types -----------------------------------------------------------------------------------

    /// <summary>A C int32 flag (0 false, anything else true), so structs holding flags stay blittable.</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct Bool32
    {
        public int Value;
        public static implicit operator bool(Bool32 b) { return b.Value != 0; }
        public static implicit operator Bool32(bool b) { return new Bool32 { Value = b ? 1 : 0 }; }
        public override string ToString() { return (Value != 0).ToString(); }
    }

    /// <summary>Packed ids (generation &lt;&lt; 32 | index); 0 is the null id.</summary>
    static class PackedId
    {
        public static string Format(string kind, ulong v)
        {
            return kind + "(" + (uint)(v & 0xffffffffu) + ", generation " + (uint)(v >> 32) + ")";
        }
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct BodyId : IEquatable<BodyId>
    {
        public ulong Value;
        public static readonly BodyId Null = new BodyId();
        public bool IsNull { get { return Value == 0; } }
        public bool Equals(BodyId o) { return Value == o.Value; }
        public override bool Equals(object o) { return o is BodyId && Equals((BodyId)o); }
        public override int GetHashCode() { return Value.GetHashCode(); }
        public static bool operator ==(BodyId a, BodyId b) { return a.Value == b.Value; }
        public static bool operator !=(BodyId a, BodyId b) { return a.Value != b.Value; }
        public override string ToString() { return PackedId.Format("BodyId", Value); }
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct JointId : IEquatable<JointId>
    {
        public ulong Value;
        public bool IsNull { get { return Value == 0; } }
        public bool Equals(JointId o) { return Value == o.Value; }
        public override bool Equals(object o) { return o is JointId && Equals((JointId)o); }
        public override int GetHashCode() { return Value.GetHashCode(); }
        public static bool operator ==(JointId a, JointId b) { return a.Value == b.Value; }
        public static bool operator !=(JointId a, JointId b) { return a.Value != b.Value; }
        public override string ToString() { return PackedId.Format("JointId", Value); }
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct HandId : IEquatable<HandId>
    {
        public ulong Value;
        public bool IsNull { get { return Value == 0; } }
        public bool Equals(HandId o) { return Value == o.Value; }
        public override bool Equals(object o) { return o is HandId && Equals((HandId)o); }
        public override int GetHashCode() { return Value.GetHashCode(); }
        public static bool operator ==(HandId a, HandId b) { return a.Value == b.Value; }
        public static bool operator !=(HandId a, HandId b) { return a.Value != b.Value; }
        public override string ToString() { return PackedId.Format("HandId", Value); }
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct Vec3
    {
        public double X, Y, Z;
        public Vec3(double x, double y, double z) { X = x; Y = y; Z = z; }
        public static Vec3 operator +(Vec3 a, Vec3 b) { return new Vec3(a.X + b.X, a.Y + b.Y, a.Z + b.Z); }
        public static Vec3 operator -(Vec3 a, Vec3 b) { return new Vec3(a.X - b.X, a.Y - b.Y, a.Z - b.Z); }
        public static Vec3 operator *(double s, Vec3 v) { return new Vec3(s * v.X, s * v.Y, s * v.Z); }
        public static double Dot(Vec3 a, Vec3 b) { return a.X * b.X + a.Y * b.Y + a.Z * b.Z; }
        public static Vec3 Cross(Vec3 a, Vec3 b)
        {
            return new Vec3(a.Y * b.Z - a.Z * b.Y, a.Z * b.X - a.X * b.Z, a.X * b.Y - a.Y * b.X);
        }
        public double Length { get { return Math.Sqrt(Dot(this, this)); } }
        public override string ToString() { return "(" + X + ", " + Y + ", " + Z + ")"; }
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct Quat
    {
        public double X, Y, Z, W;
        public Quat(double x, double y, double z, double w) { X = x; Y = y; Z = z; W = w; }
        public static readonly Quat Identity = new Quat(0, 0, 0, 1);
        public static Quat AxisAngle(Vec3 axis, double angle)
        {
            double s = Math.Sin(0.5 * angle) / axis.Length;
            return new Quat(s * axis.X, s * axis.Y, s * axis.Z, Math.Cos(0.5 * angle));
        }
        public static Quat operator *(Quat a, Quat b)
        {
            return new Quat(a.W * b.X + a.X * b.W + a.Y * b.Z - a.Z * b.Y,
                            a.W * b.Y - a.X * b.Z + a.Y * b.W + a.Z * b.X,
                            a.W * b.Z + a.X * b.Y - a.Y * b.X + a.Z * b.W,
                            a.W * b.W - a.X * b.X - a.Y * b.Y - a.Z * b.Z);
        }
        /// <summary>Rotates v (q v q*).</summary>
        public Vec3 Rotate(Vec3 v)
        {
            var u = new Vec3(X, Y, Z);
            Vec3 t = 2 * Vec3.Cross(u, v);
            return v + W * t + Vec3.Cross(u, t);
        }
        public override string ToString() { return "(" + X + ", " + Y + ", " + Z + ", " + W + ")"; }
    }

    /// <summary>x_world = Orientation * x_local + Position.</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct Pose
    {
        public Vec3 Position;
        public Quat Orientation;
        public Pose(Vec3 position, Quat orientation) { Position = position; Orientation = orientation; }
        public static readonly Pose Identity = new Pose(new Vec3(0, 0, 0), Quat.Identity);
        public override string ToString() { return "Pose(" + Position + ", " + Orientation + ")"; }
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct GraspSettings
    {
        public double CosThreshold;
        public double ReleaseDistance;
        public double TrackingGraceS;
        public double GraspTimeS;
        public double ReleaseTimeS;
        public double ClosingDistance;
        public double ClosingWindowS;
        public double OpeningDistance;
        public double SqueezeDistance;
        public double PassDepth;
        public double SlipDistance;
        public int VelocityWindow;
        public int AcrossParts;  // bool
        public double PinchReach;
        public double VelocityWindowS;

        /// <summary>The grasp rule before the hand's intent was read, for comparison (handsim_grasp_settings_contacts):
        /// ClosingDistance, OpeningDistance and PinchReach 0, every other field the default.</summary>
        public static GraspSettings Contacts
        {
            get { GraspSettings s; Native.Check(Native.handsim_grasp_settings_contacts(out s), "handsim_grasp_settings_contacts"); return s; }
        }
        /// <summary>Eq. 3 as printed in the paper, for comparison (handsim_grasp_settings_paper): Contacts with
        /// CosThreshold +0.7, AcrossParts 0, GraspTimeS and ReleaseTimeS 0.</summary>
        public static GraspSettings Paper
        {
            get { GraspSettings s; Native.Check(Native.handsim_grasp_settings_paper(out s), "handsim_grasp_settings_paper"); return s; }
        }
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct WorldSettings
    {
        public Vec3 Gravity;
        public double FixedSubstep;
        public int MaxSubsteps;
        public Bool32 Ground;
        public double GroundHeight;
        public double GroundFriction;
        public int SolverIterations;
        public int JointMaxIterations;
        public GraspSettings Grasp;
        public ParticleContacts ParticleContacts;
        public Bool32 PaperPipeline;
        public int RenderThreads;
        public PushModel PushModel;  // how a hand moves a free body it touches
        public double SkinDepth;     // m: a particle's overlap up to this presses the body as finger pulp (0: off)
        public double SkinPressure;  // Pa: the pulp's pressure at SkinDepth of compression

        /// <summary>The C++ defaults (WorldDef{}).</summary>
        public static WorldSettings Default
        {
            get { WorldSettings s; Native.Check(Native.handsim_world_settings_default(out s), "handsim_world_settings_default"); return s; }
        }
    }

    /// <summary>A collision shape; Points/Indices are filled by World.AddBody from managed arrays.</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct Shape
    {
        public ShapeType Type;
        public int PointCount;
        public Vec3 HalfExtents;
        public double Radius;
        public double HalfHeight;
        public IntPtr Points;
        public IntPtr Indices;
        public int IndexCount;
        public int Reserved;

        public static Shape Box(double hx, double hy, double hz)
        {
            return new Shape { Type = ShapeType.Box, HalfExtents = new Vec3(hx, hy, hz) };
        }
        public static Shape Sphere(double radius) { return new Shape { Type = ShapeType.Sphere, Radius = radius }; }
        public static Shape Capsule(double radius, double halfHeight)
        {
            return new Shape { Type = ShapeType.Capsule, Radius = radius, HalfHeight = halfHeight };
        }
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct BodyDef
    {
        public Shape Shape;
        public double Mass;
        public Pose Pose;
        public Vec3 LinearVelocity;
        public Vec3 AngularVelocity;
        public double Friction;
        public double Restitution;
        public Bool32 Kinematic;
        public int Reserved;

        public static BodyDef Default
        {
            get { BodyDef d; Native.Check(Native.handsim_body_def_default(out d), "handsim_body_def_default"); return d; }
        }
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct BodyInfo
    {
        public BodyMotion Motion;
        public ShapeType ShapeType;
        public double Mass;
        public Vec3 HalfExtents;
        public double Radius;
        public double HalfHeight;
        public int PointCount;
        public int IndexCount;
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct GraspInfo
    {
        public Bool32 Grasped;
        public int Reserved;
        public HandId Primary;
        public HandId Secondary;
        public Pose PrimaryRelative;
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct HingeDef
    {
        public BodyId Parent;
        public BodyId Child;
        public Vec3 PivotParent;
        public Vec3 AxisParent;
        public Vec3 PivotChild;
        public Vec3 AxisChild;
        public double Lower;
        public double Upper;
        public double Damping;
        public Quat RestOrientation;
        public Bool32 HasRestOrientation;
        public JointSolver Solver;
        public JointModel Model;
        public int Reserved;

        public static HingeDef Default
        {
            get { HingeDef d; Native.Check(Native.handsim_hinge_def_default(out d), "handsim_hinge_def_default"); return d; }
        }
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct SliderDef
    {
        public BodyId Parent;
        public BodyId Child;
        public Vec3 AnchorParent;
        public Vec3 AnchorChild;
        public Vec3 Axis;
        public double Lower;
        public double Upper;
        public double Damping;
        public Quat RestOrientation;
        public JointSolver Solver;
        public JointModel Model;

        public static SliderDef Default
        {
            get { SliderDef d; Native.Check(Native.handsim_slider_def_default(out d), "handsim_slider_def_default"); return d; }
        }
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct BallDef
    {
        public BodyId Parent;
        public BodyId Child;
        public Vec3 PivotParent;
        public Vec3 PivotChild;
        public Quat RestOrientation;
        public Vec3 ConeAxis;
        public double ConeHalfAngle;
        public double Damping;
        public Bool32 HasConeLimit;
        public JointSolver Solver;
        public JointModel Model;
        public int Reserved;

        public static BallDef Default
        {
            get { BallDef d; Native.Check(Native.handsim_ball_def_default(out d), "handsim_ball_def_default"); return d; }
        }
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct FixedDef
    {
        public BodyId Parent;
        public BodyId Child;
        public Pose Relative;
        public JointModel Model;
        public int Reserved;

        public static FixedDef Default
        {
            get { FixedDef d; Native.Check(Native.handsim_fixed_def_default(out d), "handsim_fixed_def_default"); return d; }
        }
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct JointState
    {
        public JointType Type;
        public JointModel Model;
        public JointSolver Solver;
        public Bool32 Solved;
        public BodyId Parent;
        public BodyId Child;
        public double Value;
        public double Rate;
        public Quat Rotation;
        public double Violation;
        public double Overshoot;
        public double Cost;
        public int Iterations;
        public JointTermination Termination;
        public double SolveSeconds;
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct HandDef
    {
        public HandSide Handedness;
        public int ParticleCount;
        public ParticleSampling Sampling;
        public int RenderVertices;
        public ulong Seed;
        public double ParticleRadius;

        public static HandDef Default
        {
            get { HandDef d; Native.Check(Native.handsim_hand_def_default(out d), "handsim_hand_def_default"); return d; }
        }
    }

    /// <summary>One tracked joint (OpenXR: -Z along the bone towards the tip, +Y out of the back of the hand).</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct JointPose
    {
        public Vec3 Position;
        public Quat Orientation;
        public double Radius;
        public Bool32 Valid;
        public int Reserved;
    }

    /// <summary>The C frame: Joints points at JointCount joint poses. World.Step builds these from JointPose[].</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct HandFrame
    {
        public HandSide Handedness;
        public int JointCount;
        public IntPtr Joints;
    }

    /// <summary>One hand's input to a step (handsim_hand_input): the frame that drives the hand Hand.</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct HandInput
    {
        public HandId Hand;
        public HandFrame Frame;
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct SkinnedMesh
    {
        public IntPtr Positions;
        public IntPtr Bones;
        public IntPtr Weights;
        public IntPtr Triangles;
        public int VertexCount;
        public int TriangleIndexCount;
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct HandInfo
    {
        public HandSide Handedness;
        public Bool32 Tracked;
        public int ParticleCount;
        public int VertexCount;
        public int TriangleIndexCount;
        public int Reserved;
        public double ParticleRadius;
        public Pose Palm;
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct HandPoseParams
    {
        public double CurlThumb, CurlIndex, CurlMiddle, CurlRing, CurlLittle;
        public double ThumbOpposition;
        public double Spread;
        public double Scale;

        public static HandPoseParams Default
        {
            get { HandPoseParams p; Native.Check(Native.handsim_hand_pose_params_default(out p), "handsim_hand_pose_params_default"); return p; }
        }
        /// <summary>The shape JewelryBox palms are made for.</summary>
        public static HandPoseParams LidPinch
        {
            get { HandPoseParams p; Native.Check(Native.handsim_lid_pinch_shape(out p), "handsim_lid_pinch_shape"); return p; }
        }
        /// <summary>This grip opened by `openness`: 0 the grip, 1 the open hand (curls and thumb opposition 0).</summary>
        public HandPoseParams Opened(double openness)
        {
            HandPoseParams p; Native.Check(Native.handsim_open_grip(ref this, openness, out p), "handsim_open_grip"); return p;
        }
        /// <summary>This grip `t` s after the hand began to close it over `duration` s (minimum jerk; open for
        /// t &lt;= 0). People reach open and close onto what they grasp; the default grasp rule needs it.</summary>
        public HandPoseParams Closing(double t, double duration = 0.25)
        {
            HandPoseParams p; Native.Check(Native.handsim_closing_grip(ref this, t, duration, out p), "handsim_closing_grip"); return p;
        }
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct Event
    {
        public EventType Type;
        public EventReason Reason;
        public HandId Hand;
        public BodyId Body;
        public override string ToString() { return Type + " " + Hand + " " + Body + (Reason != EventReason.None ? " " + Reason : ""); }
    }

    /// <summary>The C report; Name points into the world (valid until its next step).</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct StageReport
    {
        public double Seconds;
        public Bool32 Ran;
        public int Reserved;
        public IntPtr Name;
    }

    /// <summary>One stage of a step (handsim_step_stage): its cost, its work, or why it had none.</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct StepStage
    {
        public double Seconds;
        public Stage Stage;
        public SkipReason Skip;      // None: the stage ran
        public int Work;             // what it did, in its unit (enum_table.h, Stage)
        public int Particles;        // skinning: skinned; contacts: tested; deformation: pushed back; else 0
        public bool Ran { get { return Skip == SkipReason.None; } }
        public override string ToString() { return Stage + (Ran ? " ran " : " skip (" + Skip + ") ") + (Seconds * 1e6).ToString("F1") + " us"; }
    }

    /// <summary>What the last step did (handsim_step_report).</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct StepReport
    {
        [MarshalAs(UnmanagedType.ByValArray, SizeConst = 9)] public StepStage[] Stages;  // HANDSIM_STAGE_COUNT, by Stage
        public double DroppedSeconds;  // time beyond max_substeps dropped (StepWarning.SubstepsDropped)
        public uint Warnings;          // bit (1 << StepWarning) per warning raised; Has(w) reads one
        public int Substeps;
        public Bool32 Bullet;          // Bullet simulated the substeps (false: no dynamic body awake)
        public int NonfiniteBodies;    // non-finite body states replaced (StepWarning.NonFiniteRecovered)
        public StepStage Get(Stage s) { return Stages[(int)s]; }
        public bool Has(StepWarning w) { return (Warnings & (1u << (int)w)) != 0; }
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct JewelryBoxDef
    {
        public Vec3 Position;
        public double Yaw;
        public Vec3 BaseHalfExtents;
        public double LidHalfThickness;
        public double LidOverhang;
        public double BaseMass;
        public double LidMass;
        public double Lower;
        public double Upper;
        public double Damping;
        public double Friction;
        public Bool32 Table;
        public JointModel Model;
        public JointSolver Solver;
        public int Reserved;

        public static JewelryBoxDef Default
        {
            get { JewelryBoxDef d; Native.Check(Native.handsim_jewelry_box_def_default(out d), "handsim_jewelry_box_def_default"); return d; }
        }
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct JewelryBox
    {
        public BodyId Table;
        public BodyId Base;
        public BodyId Lid;
        public JointId Hinge;
        public JewelryBoxDef Def;
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct EnumEntry
    {
        public IntPtr EnumName;
        public IntPtr ValueName;
        public IntPtr Constant;
        public int Value;
        public int Reserved;
    }

    [StructLayout(LayoutKind.Sequential)]
    public struct LayoutEntry
    {
        public IntPtr StructName;
        public IntPtr FieldName;
        public int Offset;
        public int Size;
    }

    // --- P/Invoke ------------------------------------------------------------------------------------------------

    /// <summary>The owner of a native world: destroys it exactly once (Dispose or finalizer).</summary>
    public sealed class WorldHandle : SafeHandle
    {
        WorldHandle() : base(IntPtr.Zero, true) { }
        public override bool IsInvalid { get { return handle == IntPtr.Zero; } }
        protected override bool ReleaseHandle() { return Native.handsim_world_destroy(handle) == 0; }
    }

    public delegate int BufferCall<T>(T[] buffer, int capacity, out int count);

    public static class Native
    {
        public const string Library = "handsim";
        public const int AbiVersionMajor = 3;  // HANDSIM_ABI_VERSION_MAJOR of the handsim.h this file mirrors
        public const int HandJointCount = 26;
        const CallingConvention Cdecl = CallingConvention.Cdecl;

        /// <summary>Throws HandsimException for a non-zero status, with the calling thread's native message.</summary>
        public static void Check(int status, string call)
        {
            if (status != 0) throw new HandsimException((Status)status, LastError(), call);
        }

        public static string LastError() { return Marshal.PtrToStringAnsi(handsim_last_error()); }

        /// <summary>Fills (and grows) a managed buffer from a size-queried native array; returns the count.</summary>
        public static int Fill<T>(ref T[] buffer, BufferCall<T> call, string name)
        {
            int count;
            Check(call(null, 0, out count), name);
            if (buffer == null || buffer.Length < count) buffer = new T[count];
            Check(call(buffer, buffer.Length, out count), name);
            return count;
        }

        public static T[] Read<T>(BufferCall<T> call, string name)
        {
            T[] buffer = null;
            int count = Fill(ref buffer, call, name);
            if (buffer.Length != count) Array.Resize(ref buffer, count);
            return buffer;
        }

        // Strings the library returns are static or library-owned: IntPtr, never string (the marshaller would free them).
        [DllImport(Library, CallingConvention = Cdecl)] public static extern uint handsim_abi_version();
        [DllImport(Library, CallingConvention = Cdecl)] public static extern IntPtr handsim_version();
        [DllImport(Library, CallingConvention = Cdecl)] public static extern uint handsim_features();
        [DllImport(Library, CallingConvention = Cdecl)] public static extern IntPtr handsim_last_error();
        [DllImport(Library, CallingConvention = Cdecl)] public static extern IntPtr handsim_status_name(int status);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_layout_count(out int count);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_layout(int index, out LayoutEntry entry);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_enum_count(out int count);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_enum_value(int index, out EnumEntry entry);

        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_grasp_settings_contacts(out GraspSettings s);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_grasp_settings_paper(out GraspSettings s);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_world_settings_default(out WorldSettings s);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_body_def_default(out BodyDef d);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_hinge_def_default(out HingeDef d);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_slider_def_default(out SliderDef d);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_ball_def_default(out BallDef d);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_fixed_def_default(out FixedDef d);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_hand_def_default(out HandDef d);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_hand_pose_params_default(out HandPoseParams p);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_jewelry_box_def_default(out JewelryBoxDef d);

        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_world_create(ref WorldSettings settings, out WorldHandle world);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_world_destroy(IntPtr world);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_world_reset(WorldHandle world);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_get_world_settings(WorldHandle world, out WorldSettings settings);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_world_time(WorldHandle world, out double time);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_state_hash(WorldHandle world, out ulong hash);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_save_state(WorldHandle world, [Out] byte[] bytes, int capacity, out int count);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_restore_state(WorldHandle world, [In] byte[] bytes, int size);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_step(WorldHandle world, double dt, [In] HandFrame[] hands, int handCount);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_step_hands(WorldHandle world, double dt, [In] HandInput[] hands, int handCount);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_last_step(WorldHandle world, out StepReport report);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_stage_reports(WorldHandle world, [Out] StageReport[] reports, int capacity, out int count);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_stage_summary(WorldHandle world, [Out] byte[] text, int capacity, out int length);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_events(WorldHandle world, [Out] Event[] events, int capacity, out int count);

        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_add_body(WorldHandle world, ref BodyDef body, out BodyId id);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_remove_body(WorldHandle world, BodyId body);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_contains_body(WorldHandle world, BodyId body, out int alive);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_bodies(WorldHandle world, [Out] BodyId[] bodies, int capacity, out int count);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_get_body_info(WorldHandle world, BodyId body, out BodyInfo info);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_body_pose(WorldHandle world, BodyId body, out Pose pose);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_body_poses(WorldHandle world, [In] BodyId[] bodies, int count, [Out] Pose[] poses);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_set_body_pose(WorldHandle world, BodyId body, ref Pose pose);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_body_velocity(WorldHandle world, BodyId body, out Vec3 linear, out Vec3 angular);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_set_body_velocity(WorldHandle world, BodyId body, ref Vec3 linear, ref Vec3 angular);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_body_grasp(WorldHandle world, BodyId body, out GraspInfo grasp);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_body_contact_count(WorldHandle world, BodyId body, HandId hand, out int count);

        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_add_hinge(WorldHandle world, ref HingeDef hinge, out JointId id);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_add_slider(WorldHandle world, ref SliderDef slider, out JointId id);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_add_ball(WorldHandle world, ref BallDef ball, out JointId id);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_add_fixed(WorldHandle world, ref FixedDef fixedDef, out JointId id);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_remove_joint(WorldHandle world, JointId joint);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_contains_joint(WorldHandle world, JointId joint, out int alive);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_joints(WorldHandle world, [Out] JointId[] joints, int capacity, out int count);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_get_joint_state(WorldHandle world, JointId joint, out JointState state);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_set_joint_value(WorldHandle world, JointId joint, double value);

        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_add_hand(WorldHandle world, ref HandDef def, out HandId id);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_add_hand_with_mesh(WorldHandle world, ref HandDef def, ref SkinnedMesh mesh, ref HandFrame bind, out HandId id);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_remove_hand(WorldHandle world, HandId hand);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_contains_hand(WorldHandle world, HandId hand, out int alive);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_hands(WorldHandle world, [Out] HandId[] hands, int capacity, out int count);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_get_hand_info(WorldHandle world, HandId hand, out HandInfo info);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_hand_particles(WorldHandle world, HandId hand, int deformed, [Out] Vec3[] positions, int capacity, out int count);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_hand_render_vertices(WorldHandle world, HandId hand, [Out] Vec3[] vertices, int capacity, out int count);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_hand_render_vertices_f32(WorldHandle world, HandId hand, [Out] float[] xyz, int capacity, out int count);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_hand_triangles(WorldHandle world, HandId hand, [Out] int[] indices, int capacity, out int count);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_hand_source_vertices(WorldHandle world, HandId hand, [Out] int[] indices, int capacity, out int count);

        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_make_hand_frame(HandSide handedness, ref Pose palm, ref HandPoseParams p, [Out] JointPose[] joints, int capacity);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_bind_frame(HandSide handedness, double scale, [Out] JointPose[] joints, int capacity);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_lid_pinch_shape(out HandPoseParams p);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_open_grip(ref HandPoseParams grip, double openness, out HandPoseParams p);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_closing_grip(ref HandPoseParams grip, double t, double duration, out HandPoseParams p);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_build_jewelry_box(WorldHandle world, ref JewelryBoxDef def, out JewelryBox box);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_jewelry_box_lid_pinch_palm(WorldHandle world, ref JewelryBox box, HandSide handedness, double angle, double lift, out Pose palm);
        [DllImport(Library, CallingConvention = Cdecl)] public static extern int handsim_jewelry_box_points(WorldHandle world, ref JewelryBox box, out Vec3 lidFront, out Vec3 hingePivot, out Vec3 hingeAxis);

        /// <summary>Throws unless the loaded library has this file's ABI major.</summary>
        public static void EnsureCompatible()
        {
            uint abi = handsim_abi_version();
            if ((abi >> 16) != AbiVersionMajor)
                throw new HandsimException(Status.Unsupported, "libhandsim has ABI " + (abi >> 16) + "." + (abi & 0xffff) +
                                           ", this wrapper needs " + AbiVersionMajor + ".x", "handsim_abi_version");
        }
    }

    // --- the idiomatic layer -------------------------------------------------------------------------------------

    /// <summary>Pins managed arrays for the duration of one native call.</summary>
    struct Pinned : IDisposable
    {
        GCHandle handle;
        public IntPtr Address { get { return handle.IsAllocated ? handle.AddrOfPinnedObject() : IntPtr.Zero; } }
        public Pinned(object array) { handle = array != null ? GCHandle.Alloc(array, GCHandleType.Pinned) : default(GCHandle); }
        public void Dispose() { if (handle.IsAllocated) handle.Free(); }
    }

    /// <summary>Synthetic hands (the tests' and samples' tracked-hand stand-ins).</summary>
    public static class Hands
    {
        /// <summary>An adult hand with its palm joint at `palm` (26 joints in OpenXR order) into `joints`.</summary>
        public static void MakeFrame(HandSide handedness, Pose palm, HandPoseParams shape, JointPose[] joints)
        {
            Native.Check(Native.handsim_make_hand_frame(handedness, ref palm, ref shape, joints, joints == null ? 0 : joints.Length),
                         "handsim_make_hand_frame");
        }

        public static JointPose[] MakeFrame(HandSide handedness, Pose palm, HandPoseParams shape)
        {
            var joints = new JointPose[Native.HandJointCount];
            MakeFrame(handedness, palm, shape, joints);
            return joints;
        }

        /// <summary>The flat hand at the identity palm pose (the procedural mesh's bind pose).</summary>
        public static JointPose[] BindFrame(HandSide handedness, double scale = 1.0)
        {
            var joints = new JointPose[Native.HandJointCount];
            Native.Check(Native.handsim_bind_frame(handedness, scale, joints, joints.Length), "handsim_bind_frame");
            return joints;
        }
    }

    /// <summary>One hand's input for World.Step: its handedness and 26 joints (OpenXR order), reused every frame.</summary>
    public sealed class TrackedHand
    {
        /// <summary>The hand this frame drives (World.StepHands); AddHand's id.</summary>
        public HandId Hand;
        public HandSide Handedness;
        public readonly JointPose[] Joints = new JointPose[Native.HandJointCount];
        public TrackedHand(HandId hand, HandSide handedness) { Hand = hand; Handedness = handedness; }
        /// <summary>Without a hand id: only for the deprecated World.Step(dt, hands), which goes by position.</summary>
        public TrackedHand(HandSide handedness) { Handedness = handedness; }
    }

    /// <summary>A handsim world. Not thread-safe: use one world from one thread at a time.</summary>
    public sealed class World : IDisposable
    {
        readonly WorldHandle handle;
        HandFrame[] frames = new HandFrame[0];
        HandInput[] inputs = new HandInput[0];
        GCHandle[] pins = new GCHandle[0];
        readonly TrackedHand[] one = new TrackedHand[1], two = new TrackedHand[2];  // Step's allocation-free overloads

        public World() : this(WorldSettings.Default) { }

        public World(WorldSettings settings)
        {
            Native.EnsureCompatible();
            Native.Check(Native.handsim_world_create(ref settings, out handle), "handsim_world_create");
        }

        public WorldHandle Handle { get { return handle; } }
        public void Dispose() { handle.Dispose(); }

        public WorldSettings Settings
        {
            get { WorldSettings s; Native.Check(Native.handsim_get_world_settings(handle, out s), "handsim_get_world_settings"); return s; }
        }
        public double Time { get { double t; Native.Check(Native.handsim_world_time(handle, out t), "handsim_world_time"); return t; } }
        public ulong StateHash { get { ulong h; Native.Check(Native.handsim_state_hash(handle, out h), "handsim_state_hash"); return h; } }
        public void Reset() { Native.Check(Native.handsim_world_reset(handle), "handsim_world_reset"); }

        /// <summary>The world's state as bytes; this world and every world restored from them continue bit for
        /// bit alike (docs/design.md "Save and restore").</summary>
        public byte[] SaveState()
        {
            return Native.Read<byte>((byte[] b, int capacity, out int count) => Native.handsim_save_state(handle, b, capacity, out count), "handsim_save_state");
        }
        /// <summary>Restores SaveState's bytes into a world built alike; bad bytes throw naming "state".</summary>
        public void RestoreState(byte[] state)
        {
            Native.Check(Native.handsim_restore_state(handle, state, state == null ? 0 : state.Length), "handsim_restore_state");
        }

        // --- stepping ---

        /// <summary>One frame with no tracked hands.</summary>
        public void Step(double dt) { StepHands(dt, (TrackedHand[])null); }

        /// <summary>One frame: hand.Joints drive the hand hand.Hand (the others untracked). Unlike
        /// StepHands(dt, params ...) with one argument, it allocates nothing: a frame loop calls this, or passes an
        /// array it keeps.</summary>
        public void StepHands(double dt, TrackedHand hand)
        {
            one[0] = hand;
            try { StepHands(dt, one); }
            finally { one[0] = null; }
        }

        /// <summary>One frame driving two hands, each the one its Hand names; allocates nothing (see
        /// StepHands(dt, hand)).</summary>
        public void StepHands(double dt, TrackedHand first, TrackedHand second)
        {
            two[0] = first; two[1] = second;
            try { StepHands(dt, two); }
            finally { two[0] = two[1] = null; }
        }

        /// <summary>One frame: each hands[k] drives the hand hands[k].Hand; live hands without an entry are
        /// untracked. A stale or repeated id throws naming hands[k].hand, a bad frame hands[k].frame.&lt;field&gt;.
        /// Pins each hand's joints for the call; allocates nothing once the world has seen this many hands.</summary>
        public void StepHands(double dt, params TrackedHand[] hands)
        {
            int n = Pin(hands);
            if (inputs.Length < n) inputs = new HandInput[n];
            try
            {
                for (int i = 0; i < n; ++i) inputs[i] = new HandInput { Hand = hands[i].Hand, Frame = frames[i] };
                Native.Check(Native.handsim_step_hands(handle, dt, inputs, n), "handsim_step_hands");
            }
            finally { Unpin(n); }
        }

        /// <summary>Deprecated (kept through ABI 3.x, removed at 4.0): hands[i] drives the i-th hand of Hands(),
        /// which a removed and re-added hand reorders, so a frame can drive another hand than meant; use
        /// StepHands.</summary>
        [Obsolete("Step(dt, hands) goes by the order of Hands(); use StepHands, whose frames name their hand")]
        public void Step(double dt, params TrackedHand[] hands)
        {
            int n = Pin(hands);
            try { Native.Check(Native.handsim_step(handle, dt, frames, n), "handsim_step"); }
            finally { Unpin(n); }
        }

        // Pins each hand's joints into frames[i] for one call; returns the count. Unpin(n) releases them.
        int Pin(TrackedHand[] hands)
        {
            int n = hands == null ? 0 : hands.Length;
            for (int i = 0; i < n; ++i)
                if (hands[i] == null) throw new ArgumentNullException("hands", "hands[" + i + "] is null");
            if (frames.Length < n) { frames = new HandFrame[n]; pins = new GCHandle[n]; }
            try
            {
                for (int i = 0; i < n; ++i)
                {
                    pins[i] = GCHandle.Alloc(hands[i].Joints, GCHandleType.Pinned);
                    frames[i] = new HandFrame { Handedness = hands[i].Handedness, JointCount = hands[i].Joints.Length,
                                                Joints = pins[i].AddrOfPinnedObject() };
                }
            }
            catch { Unpin(n); throw; }
            return n;
        }

        void Unpin(int n)
        {
            for (int i = 0; i < n; ++i) if (pins[i].IsAllocated) pins[i].Free();
        }

        /// <summary>What the last step did: per stage its cost and work or skip reason, and the warnings.</summary>
        public StepReport LastStep()
        {
            StepReport r;
            Native.Check(Native.handsim_last_step(handle, out r), "handsim_last_step");
            return r;
        }

        public string StageSummary()
        {
            byte[] text = Native.Read<byte>((byte[] b, int c, out int n) => Native.handsim_stage_summary(handle, b, c, out n),
                                            "handsim_stage_summary");
            return System.Text.Encoding.UTF8.GetString(text, 0, Math.Max(0, text.Length - 1));
        }

        // The frame-loop readers (Events, HandParticles, HandRenderVertices[F32]) call the library directly instead of
        // through Native.Fill: a lambda capturing the handle would allocate a closure and a delegate on every call.
        /// <summary>Events of the last step into `buffer` (grown when needed); returns their number.</summary>
        public int Events(ref Event[] buffer)
        {
            int count;
            Native.Check(Native.handsim_events(handle, null, 0, out count), "handsim_events");
            if (buffer == null || buffer.Length < count) buffer = new Event[count];
            Native.Check(Native.handsim_events(handle, buffer, buffer.Length, out count), "handsim_events");
            return count;
        }

        public Event[] Events()
        {
            return Native.Read<Event>((Event[] b, int c, out int n) => Native.handsim_events(handle, b, c, out n), "handsim_events");
        }

        // --- bodies ---

        /// <summary>Adds a body; hull points / mesh vertices and indices come from the arrays (pinned for the call).</summary>
        public BodyId AddBody(BodyDef def, Vec3[] points = null, int[] indices = null)
        {
            using (var p = new Pinned(points))
            using (var i = new Pinned(indices))
            {
                if (points != null) { def.Shape.Points = p.Address; def.Shape.PointCount = points.Length; }
                if (indices != null) { def.Shape.Indices = i.Address; def.Shape.IndexCount = indices.Length; }
                BodyId id;
                Native.Check(Native.handsim_add_body(handle, ref def, out id), "handsim_add_body");
                return id;
            }
        }

        public void RemoveBody(BodyId body) { Native.Check(Native.handsim_remove_body(handle, body), "handsim_remove_body"); }
        public bool Contains(BodyId body) { int a; Native.Check(Native.handsim_contains_body(handle, body, out a), "handsim_contains_body"); return a != 0; }
        public BodyId[] Bodies()
        {
            return Native.Read<BodyId>((BodyId[] b, int c, out int n) => Native.handsim_bodies(handle, b, c, out n), "handsim_bodies");
        }
        public BodyInfo BodyInfo(BodyId body) { BodyInfo i; Native.Check(Native.handsim_get_body_info(handle, body, out i), "handsim_get_body_info"); return i; }
        public Pose BodyPose(BodyId body) { Pose p; Native.Check(Native.handsim_body_pose(handle, body, out p), "handsim_body_pose"); return p; }

        /// <summary>Poses of many bodies in one native call (a frame loop's read-back).</summary>
        public void BodyPoses(BodyId[] bodies, Pose[] poses)
        {
            if (bodies == null || poses == null || poses.Length < bodies.Length)
                throw new ArgumentException("poses must hold one pose per body");
            Native.Check(Native.handsim_body_poses(handle, bodies, bodies.Length, poses), "handsim_body_poses");
        }

        public void SetBodyPose(BodyId body, Pose pose) { Native.Check(Native.handsim_set_body_pose(handle, body, ref pose), "handsim_set_body_pose"); }
        public void BodyVelocity(BodyId body, out Vec3 linear, out Vec3 angular)
        {
            Native.Check(Native.handsim_body_velocity(handle, body, out linear, out angular), "handsim_body_velocity");
        }
        public void SetBodyVelocity(BodyId body, Vec3 linear, Vec3 angular)
        {
            Native.Check(Native.handsim_set_body_velocity(handle, body, ref linear, ref angular), "handsim_set_body_velocity");
        }
        public GraspInfo BodyGrasp(BodyId body) { GraspInfo g; Native.Check(Native.handsim_body_grasp(handle, body, out g), "handsim_body_grasp"); return g; }
        public int BodyContactCount(BodyId body, HandId hand)
        {
            int n; Native.Check(Native.handsim_body_contact_count(handle, body, hand, out n), "handsim_body_contact_count"); return n;
        }

        // --- joints ---

        public JointId AddHinge(HingeDef def) { JointId id; Native.Check(Native.handsim_add_hinge(handle, ref def, out id), "handsim_add_hinge"); return id; }
        public JointId AddSlider(SliderDef def) { JointId id; Native.Check(Native.handsim_add_slider(handle, ref def, out id), "handsim_add_slider"); return id; }
        public JointId AddBall(BallDef def) { JointId id; Native.Check(Native.handsim_add_ball(handle, ref def, out id), "handsim_add_ball"); return id; }
        public JointId AddFixed(FixedDef def) { JointId id; Native.Check(Native.handsim_add_fixed(handle, ref def, out id), "handsim_add_fixed"); return id; }
        public void RemoveJoint(JointId joint) { Native.Check(Native.handsim_remove_joint(handle, joint), "handsim_remove_joint"); }
        public bool Contains(JointId joint) { int a; Native.Check(Native.handsim_contains_joint(handle, joint, out a), "handsim_contains_joint"); return a != 0; }
        public JointId[] Joints()
        {
            return Native.Read<JointId>((JointId[] b, int c, out int n) => Native.handsim_joints(handle, b, c, out n), "handsim_joints");
        }
        public JointState JointState(JointId joint) { JointState s; Native.Check(Native.handsim_get_joint_state(handle, joint, out s), "handsim_get_joint_state"); return s; }
        public void SetJointValue(JointId joint, double value) { Native.Check(Native.handsim_set_joint_value(handle, joint, value), "handsim_set_joint_value"); }

        // --- hands ---

        public HandId AddHand(HandDef def) { HandId id; Native.Check(Native.handsim_add_hand(handle, ref def, out id), "handsim_add_hand"); return id; }

        /// <summary>A hand with your skinned mesh (4 bones and weights per vertex), bound at `bind` (26 valid joints).</summary>
        public HandId AddHand(HandDef def, Vec3[] positions, int[] bones, double[] weights, int[] triangles, JointPose[] bind)
        {
            using (var p = new Pinned(positions))
            using (var b = new Pinned(bones))
            using (var w = new Pinned(weights))
            using (var t = new Pinned(triangles))
            using (var j = new Pinned(bind))
            {
                var mesh = new SkinnedMesh { Positions = p.Address, Bones = b.Address, Weights = w.Address, Triangles = t.Address,
                                             VertexCount = positions == null ? 0 : positions.Length,
                                             TriangleIndexCount = triangles == null ? 0 : triangles.Length };
                var frame = new HandFrame { Handedness = def.Handedness, JointCount = bind == null ? 0 : bind.Length, Joints = j.Address };
                HandId id;
                Native.Check(Native.handsim_add_hand_with_mesh(handle, ref def, ref mesh, ref frame, out id), "handsim_add_hand_with_mesh");
                return id;
            }
        }

        public void RemoveHand(HandId hand) { Native.Check(Native.handsim_remove_hand(handle, hand), "handsim_remove_hand"); }
        public bool Contains(HandId hand) { int a; Native.Check(Native.handsim_contains_hand(handle, hand, out a), "handsim_contains_hand"); return a != 0; }
        public HandId[] Hands()
        {
            return Native.Read<HandId>((HandId[] b, int c, out int n) => Native.handsim_hands(handle, b, c, out n), "handsim_hands");
        }
        public HandInfo HandInfo(HandId hand) { HandInfo i; Native.Check(Native.handsim_get_hand_info(handle, hand, out i), "handsim_get_hand_info"); return i; }

        /// <summary>Particle centres (tracked, or deformed as drawn) into `buffer` (grown when needed); returns the count.</summary>
        public int HandParticles(HandId hand, bool deformed, ref Vec3[] buffer)
        {
            int count, flag = deformed ? 1 : 0;
            Native.Check(Native.handsim_hand_particles(handle, hand, flag, null, 0, out count), "handsim_hand_particles");
            if (buffer == null || buffer.Length < count) buffer = new Vec3[count];
            Native.Check(Native.handsim_hand_particles(handle, hand, flag, buffer, buffer.Length, out count), "handsim_hand_particles");
            return count;
        }

        /// <summary>Skinned, deformed render vertices in double precision; returns the count.</summary>
        public int HandRenderVertices(HandId hand, ref Vec3[] buffer)
        {
            int count;
            Native.Check(Native.handsim_hand_render_vertices(handle, hand, null, 0, out count), "handsim_hand_render_vertices");
            if (buffer == null || buffer.Length < count) buffer = new Vec3[count];
            Native.Check(Native.handsim_hand_render_vertices(handle, hand, buffer, buffer.Length, out count), "handsim_hand_render_vertices");
            return count;
        }

        /// <summary>Render vertices as float x, y, z triples (for a GPU mesh); returns the vertex count.</summary>
        public int HandRenderVerticesF32(HandId hand, ref float[] xyz)
        {
            int count;
            Native.Check(Native.handsim_hand_render_vertices_f32(handle, hand, null, 0, out count), "handsim_hand_render_vertices_f32");
            if (xyz == null || xyz.Length < 3 * count) xyz = new float[3 * count];
            Native.Check(Native.handsim_hand_render_vertices_f32(handle, hand, xyz, xyz.Length / 3, out count), "handsim_hand_render_vertices_f32");
            return count;
        }

        /// <summary>Triangle indices of the render mesh (model vertex order), counter-clockwise from outside.</summary>
        public int[] HandTriangles(HandId hand)
        {
            return Native.Read<int>((int[] b, int c, out int n) => Native.handsim_hand_triangles(handle, hand, b, c, out n), "handsim_hand_triangles");
        }

        /// <summary>For each render vertex, the index of the vertex in the mesh given to AddHand (or generated).</summary>
        public int[] HandSourceVertices(HandId hand)
        {
            return Native.Read<int>((int[] b, int c, out int n) => Native.handsim_hand_source_vertices(handle, hand, b, c, out n),
                                    "handsim_hand_source_vertices");
        }

        // --- the shared scene ---

        public JewelryBox BuildJewelryBox() { return BuildJewelryBox(JewelryBoxDef.Default); }
        public JewelryBox BuildJewelryBox(JewelryBoxDef def)
        {
            JewelryBox box;
            Native.Check(Native.handsim_build_jewelry_box(handle, ref def, out box), "handsim_build_jewelry_box");
            return box;
        }

        /// <summary>The palm pose of a hand pinching the lid's lip, swung about the hinge by `angle` (rad).</summary>
        public Pose LidPinchPalm(JewelryBox box, HandSide handedness, double angle, double lift = 0)
        {
            Pose palm;
            Native.Check(Native.handsim_jewelry_box_lid_pinch_palm(handle, ref box, handedness, angle, lift, out palm),
                         "handsim_jewelry_box_lid_pinch_palm");
            return palm;
        }

        public void JewelryBoxPoints(JewelryBox box, out Vec3 lidFront, out Vec3 hingePivot, out Vec3 hingeAxis)
        {
            Native.Check(Native.handsim_jewelry_box_points(handle, ref box, out lidFront, out hingePivot, out hingeAxis),
                         "handsim_jewelry_box_points");
        }
    }

    /// <summary>
    /// handsim (right-handed, Y up, OpenXR) and Unity (left-handed, Y up) describe the same space with Z mirrored:
    /// a position maps to (x, y, -z) and a rotation to (-x, -y, z, w), both ways (each map is its own inverse).
    /// Triangles change winding. Joint axes: OpenXR's -Z along the bone becomes Unity's +Z (forward).
    /// </summary>
    public static class UnityConvert
    {
        public static Vec3 ToUnity(Vec3 p) { return new Vec3(p.X, p.Y, -p.Z); }
        public static Vec3 FromUnity(Vec3 p) { return new Vec3(p.X, p.Y, -p.Z); }
        public static Quat ToUnity(Quat q) { return new Quat(-q.X, -q.Y, q.Z, q.W); }
        public static Quat FromUnity(Quat q) { return new Quat(-q.X, -q.Y, q.Z, q.W); }
        public static Pose ToUnity(Pose p) { return new Pose(ToUnity(p.Position), ToUnity(p.Orientation)); }
        public static Pose FromUnity(Pose p) { return new Pose(FromUnity(p.Position), FromUnity(p.Orientation)); }

        /// <summary>Components of a Unity Vector3 / Quaternion (floats) without referencing UnityEngine.</summary>
        public static void ToUnity(Vec3 p, out float x, out float y, out float z) { x = (float)p.X; y = (float)p.Y; z = (float)-p.Z; }
        public static void ToUnity(Quat q, out float x, out float y, out float z, out float w)
        {
            x = (float)-q.X; y = (float)-q.Y; z = (float)q.Z; w = (float)q.W;
        }
        public static Vec3 PositionFromUnity(float x, float y, float z) { return new Vec3(x, y, -(double)z); }
        public static Quat RotationFromUnity(float x, float y, float z, float w) { return new Quat(-(double)x, -(double)y, z, w); }

        /// <summary>The UnityEngine.XR.Hands.XRHandJointID value of OpenXR joint `openXrIndex` (palm 0, wrist 1, ...).</summary>
        public static int XRHandJointID(int openXrIndex)
        {
            if (openXrIndex < 0 || openXrIndex >= Native.HandJointCount) throw new ArgumentOutOfRangeException("openXrIndex");
            return openXrIndex == 0 ? 2 : openXrIndex == 1 ? 1 : openXrIndex + 1;
        }

        /// <summary>
        /// One hand's joints from Unity space into `joints` (OpenXR order): positions xyz and rotations xyzw per joint,
        /// as floats, in OpenXR order (use XRHandJointID to gather them); radii and valid flags may be null (1 cm, valid).
        /// </summary>
        public static void JointsFromUnity(float[] positions, float[] rotations, float[] radii, bool[] valid, JointPose[] joints)
        {
            int n = Native.HandJointCount;
            if (positions == null || positions.Length < 3 * n) throw new ArgumentException("positions: needs 3 x 26 floats");
            if (rotations == null || rotations.Length < 4 * n) throw new ArgumentException("rotations: needs 4 x 26 floats");
            if (joints == null || joints.Length < n) throw new ArgumentException("joints: needs 26 joint poses");
            for (int j = 0; j < n; ++j)
            {
                joints[j].Position = PositionFromUnity(positions[3 * j], positions[3 * j + 1], positions[3 * j + 2]);
                joints[j].Orientation = RotationFromUnity(rotations[4 * j], rotations[4 * j + 1], rotations[4 * j + 2], rotations[4 * j + 3]);
                joints[j].Radius = radii != null ? radii[j] : 0.01;
                joints[j].Valid = valid == null || valid[j];
            }
        }

        /// <summary>handsim float x, y, z triples (e.g. HandRenderVerticesF32) to Unity space, in place.</summary>
        public static void VerticesToUnity(float[] xyz, int vertexCount)
        {
            for (int i = 0; i < vertexCount; ++i) xyz[3 * i + 2] = -xyz[3 * i + 2];
        }

        /// <summary>Triangle indices with their winding reversed, for Unity's clockwise front faces.</summary>
        public static int[] TrianglesToUnity(int[] triangles)
        {
            var result = (int[])triangles.Clone();
            for (int i = 0; i + 2 < result.Length; i += 3) { int t = result[i + 1]; result[i + 1] = result[i + 2]; result[i + 2] = t; }
            return result;
        }
    }
}
