// The C# test (ctest csharp_abi): compiled with mcs together with bindings/csharp/Handsim.cs and run under mono
// against the freshly built libhandsim.
//
//   CSharpTest.exe <c_host_hash_file>
//
// Checks: Marshal.SizeOf/OffsetOf of every struct against the library's layout table; the jewelry-box scenario
// (tests/c_abi/scenario.h, repeated below) gives the C host's state_hash; bad inputs raise HandsimException with
// the documented status and message and leave the world unchanged; the Unity conversions both ways; a hand with
// a caller-supplied skinned mesh; disposal.
using System;
using System.Collections.Generic;
using System.Diagnostics;
using System.IO;
using System.Reflection;
using System.Runtime.InteropServices;
using Handsim;

static class CSharpTest
{
    // scenario.h: 60 Hz; the hand arrives open and closes its pinch over 0.25 s, from frame 20 a 2 s swing to
    // 100 degrees, 20 frames holding.
    const int Frames = 160;
    const double Dt = 1.0 / 60.0;
    const double ClosingS = 0.25;
    const int SwingFrom = 20;

    static double ScenarioAngle(int frame)
    {
        double t = (frame - SwingFrom) / 120.0;
        if (t < 0.0) t = 0.0;
        if (t > 1.0) t = 1.0;
        return t * (100.0 * Math.PI / 180.0);
    }

    // Frame i of the scenario's right hand: the lid pinch closing onto the lip (scenario_grip_t), then swung.
    static void ScenarioHand(World world, JewelryBox box, int frame, TrackedHand input)
    {
        HandPoseParams shape = HandPoseParams.LidPinch.Closing(frame * Dt, ClosingS);
        Hands.MakeFrame(HandSide.Right, world.LidPinchPalm(box, HandSide.Right, ScenarioAngle(frame)), shape, input.Joints);
    }

    static int checks, failures;

    static void Check(bool ok, string what)
    {
        ++checks;
        if (ok) return;
        ++failures;
        Console.Error.WriteLine("FAIL: " + what);
    }

    // The call must throw HandsimException(status) whose native message starts with `prefix`, and leave the world's
    // state hash unchanged (world may be null).
    static void Rejects(World world, Action call, Status status, string prefix)
    {
        ulong before = world != null ? world.StateHash : 0;
        try
        {
            call();
            Check(false, "no exception, expected " + status + " \"" + prefix + "...\"");
        }
        catch (HandsimException e)
        {
            bool ok = e.Status == status && e.NativeMessage.StartsWith(prefix, StringComparison.Ordinal);
            Check(ok, "got " + e.Status + " \"" + e.NativeMessage + "\", expected " + status + " \"" + prefix + "...\"");
            if (ok) Console.WriteLine("  rejected as documented: " + e.Status + ": " + e.NativeMessage);
        }
        if (world != null) Check(world.StateHash == before, "the world changed after a rejected call (" + prefix + ")");
    }

    // --- layouts ---------------------------------------------------------------------------------------------------

    static readonly Dictionary<string, Type> CStructs = new Dictionary<string, Type>
    {
        {"handsim_vec3", typeof(Vec3)}, {"handsim_quat", typeof(Quat)}, {"handsim_pose", typeof(Pose)},
        {"handsim_grasp_settings", typeof(GraspSettings)}, {"handsim_world_settings", typeof(WorldSettings)},
        {"handsim_shape", typeof(Shape)}, {"handsim_body_def", typeof(BodyDef)}, {"handsim_body_info", typeof(BodyInfo)},
        {"handsim_grasp_info", typeof(GraspInfo)}, {"handsim_hinge_def", typeof(HingeDef)},
        {"handsim_slider_def", typeof(SliderDef)}, {"handsim_ball_def", typeof(BallDef)},
        {"handsim_fixed_def", typeof(FixedDef)}, {"handsim_joint_state", typeof(JointState)},
        {"handsim_hand_def", typeof(HandDef)}, {"handsim_joint_pose", typeof(JointPose)},
        {"handsim_hand_frame", typeof(HandFrame)}, {"handsim_hand_input", typeof(HandInput)},
        {"handsim_skinned_mesh", typeof(SkinnedMesh)},
        {"handsim_hand_info", typeof(HandInfo)}, {"handsim_hand_pose_params", typeof(HandPoseParams)},
        {"handsim_event", typeof(Event)}, {"handsim_stage_report", typeof(StageReport)}, {"handsim_step_stage", typeof(StepStage)},
        {"handsim_step_report", typeof(StepReport)},
        {"handsim_jewelry_box_def", typeof(JewelryBoxDef)}, {"handsim_jewelry_box", typeof(JewelryBox)},
        {"handsim_layout_entry", typeof(LayoutEntry)}, {"handsim_enum_entry", typeof(EnumEntry)},
    };

    // "LinearVelocity" -> "linear_velocity"
    static string Snake(string pascal)
    {
        var sb = new System.Text.StringBuilder();
        for (int i = 0; i < pascal.Length; ++i)
        {
            if (i > 0 && char.IsUpper(pascal[i])) sb.Append('_');
            sb.Append(char.ToLowerInvariant(pascal[i]));
        }
        return sb.ToString();
    }

    static int NativeSize(Type t) { return Marshal.SizeOf(t.IsEnum ? Enum.GetUnderlyingType(t) : t); }
    // A field's native size; a fixed array (ByValArray) is SizeConst elements.
    static int NativeSize(FieldInfo f)
    {
        if (!f.FieldType.IsArray) return NativeSize(f.FieldType);
        var m = (MarshalAsAttribute)Attribute.GetCustomAttribute(f, typeof(MarshalAsAttribute));
        return (m == null ? 0 : m.SizeConst) * NativeSize(f.FieldType.GetElementType());
    }

    static void TestLayouts()
    {
        int count;
        Native.Check(Native.handsim_layout_count(out count), "handsim_layout_count");
        var seen = new HashSet<string>();
        int rows = 0;
        for (int i = 0; i < count; ++i)
        {
            LayoutEntry e;
            Native.Check(Native.handsim_layout(i, out e), "handsim_layout");
            string s = Marshal.PtrToStringAnsi(e.StructName);
            string f = e.FieldName == IntPtr.Zero ? null : Marshal.PtrToStringAnsi(e.FieldName);
            Type type;
            if (!CStructs.TryGetValue(s, out type)) { Check(false, "no C# struct for " + s); continue; }
            if (f == null)
            {
                int size = Marshal.SizeOf(type);
                Check(size == e.Size, s + ": Marshal.SizeOf(" + type.Name + ") = " + size + ", C sizeof = " + e.Size);
                seen.Add(s);
                ++rows;
                continue;
            }
            FieldInfo field = null;
            foreach (FieldInfo fi in type.GetFields(BindingFlags.Instance | BindingFlags.Public | BindingFlags.NonPublic))
                if (Snake(fi.Name) == f) field = fi;
            if (field == null) { Check(false, s + "." + f + ": no C# field"); continue; }
            int offset = Marshal.OffsetOf(type, field.Name).ToInt32();
            int fsize = NativeSize(field);
            Check(offset == e.Offset && fsize == e.Size, s + "." + f + ": C# offset " + offset + " size " + fsize +
                  ", C offset " + e.Offset + " size " + e.Size);
            seen.Add(s + "." + f);
            ++rows;
        }
        foreach (KeyValuePair<string, Type> kv in CStructs)
        {
            Check(seen.Contains(kv.Key), kv.Key + " is missing from the library's layout table");
            foreach (FieldInfo fi in kv.Value.GetFields(BindingFlags.Instance | BindingFlags.Public | BindingFlags.NonPublic))
                Check(seen.Contains(kv.Key + "." + Snake(fi.Name)), kv.Key + " has no field for C# " + kv.Value.Name + "." + fi.Name);
        }
        Console.WriteLine("layouts: " + rows + " rows of " + CStructs.Count + " structs match Marshal.SizeOf/OffsetOf");
    }

    // C# names that differ from the core's: XR Hands' Handedness made a script using both fail (CS0104).
    static readonly Dictionary<string, string> CSharpEnumNames = new Dictionary<string, string> { {"Handedness", "HandSide"} };

    // Every row of the library's enum table (core/include/handsim/enum_table.h) must be a value of the C# enum of
    // that name with that number, and every C# enum of the wrapper must hold no value the table lacks.
    static void TestEnums()
    {
        int count;
        Native.Check(Native.handsim_enum_count(out count), "handsim_enum_count");
        var perEnum = new Dictionary<string, int>();
        Assembly wrapper = typeof(World).Assembly;
        for (int i = 0; i < count; ++i)
        {
            EnumEntry e;
            Native.Check(Native.handsim_enum_value(i, out e), "handsim_enum_value");
            string type = Marshal.PtrToStringAnsi(e.EnumName), name = Marshal.PtrToStringAnsi(e.ValueName);
            if (CSharpEnumNames.ContainsKey(type)) type = CSharpEnumNames[type];
            Type t = wrapper.GetType("Handsim." + type);
            if (t == null || !t.IsEnum) { Check(false, "no C# enum Handsim." + type); continue; }
            string csName = Enum.GetName(t, e.Value);
            Check(csName == name, type + " " + e.Value + ": C# names it " + (csName ?? "nothing") + ", the core " + name);
            perEnum[type] = perEnum.ContainsKey(type) ? perEnum[type] + 1 : 1;
        }
        int enums = 0;
        foreach (Type t in wrapper.GetTypes())
        {
            if (!t.IsEnum || t.Namespace != "Handsim" || !t.IsPublic) continue;
            ++enums;
            int rows;
            Check(perEnum.TryGetValue(t.Name, out rows), "C# enum " + t.Name + " is not in the library's enum table");
            Check(Enum.GetValues(t).Length == rows, "C# enum " + t.Name + " has " + Enum.GetValues(t).Length +
                  " values, the table " + rows);
        }
        Check(enums == perEnum.Count, "C# declares " + enums + " enums, the table " + perEnum.Count);
        Console.WriteLine("enums: " + count + " values of " + perEnum.Count + " enums match the library's table");
    }

    // --- the scenario ------------------------------------------------------------------------------------------------

    static ulong RunScenario(bool report)
    {
        using (var world = new World())
        {
            JewelryBox box = world.BuildJewelryBox();
            HandId hand = world.AddHand(HandDef.Default);
            var input = new TrackedHand(hand, HandSide.Right);
            Event[] events = null;
            double maxAngle = double.MinValue, minAngle = double.MaxValue, maxViolation = 0;
            int grasped = 0, graspBegins = 0;
            var watch = new Stopwatch();
            var stepSeconds = new List<double>();
            var outsideSeconds = new List<double>();  // World.Step's wall time minus the time the core's stages report
            for (int i = 0; i < Frames; ++i)
            {
                ScenarioHand(world, box, i, input);
                watch.Restart();
                world.StepHands(Dt, input);
                watch.Stop();
                stepSeconds.Add(watch.Elapsed.TotalSeconds);
                double inStages = 0;
                foreach (StepStage st in world.LastStep().Stages) inStages += st.Seconds;
                outsideSeconds.Add(watch.Elapsed.TotalSeconds - inStages);
                JointState s = world.JointState(box.Hinge);
                maxAngle = Math.Max(maxAngle, s.Value);
                minAngle = Math.Min(minAngle, s.Value);
                maxViolation = Math.Max(maxViolation, s.Violation);
                if (world.BodyGrasp(box.Lid).Grasped) ++grasped;
                int n = world.Events(ref events);
                for (int k = 0; k < n; ++k)
                    if (events[k].Type == EventType.GraspBegin && events[k].Body == box.Lid && events[k].Hand == hand) ++graspBegins;
            }
            if (report)
            {
                const double deg = Math.PI / 180.0;
                Console.WriteLine("jewelry box: lid angle max " + (maxAngle / deg).ToString("F4") + " deg, min " +
                                  (minAngle / deg).ToString("F4") + " deg; max violation " + maxViolation.ToString("G3") +
                                  " m; grasped " + grasped + " of " + Frames + " frames; World.Step median " +
                                  (1e6 * Median(stepSeconds)).ToString("F2") + " us, outside the core's stages " +
                                  (1e6 * Median(outsideSeconds)).ToString("F2") + " us");
                Check(maxAngle > 60 * deg, "the lid opened only to " + maxAngle / deg + " deg");
                Check(minAngle >= 0 && maxAngle <= 90 * deg + 1e-12, "the lid left [0, 90] deg");
                Check(maxViolation <= 1e-9, "hinge violation " + maxViolation);
                Check(grasped > Frames / 2, "grasped in only " + grasped + " frames");
                Check(graspBegins == 1, graspBegins + " grasp-begin events");
                StepReport last = world.LastStep();
                Check(last.Stages.Length == 9 && last.Get(Stage.Skinning).Ran && last.Get(Stage.Skinning).Work == 1,
                      "last step: " + last.Get(Stage.Skinning));
                Check(world.StageSummary().Contains("dynamics"), "stage summary");
                Vec3[] particles = null, deformed = null;
                int np = world.HandParticles(hand, false, ref particles);
                world.HandParticles(hand, true, ref deformed);
                int moved = 0;
                for (int k = 0; k < np; ++k) if (particles[k].X != deformed[k].X || particles[k].Y != deformed[k].Y || particles[k].Z != deformed[k].Z) ++moved;
                Check(np == world.HandInfo(hand).ParticleCount && moved > 0, "particles: " + np + ", deformed " + moved);
                float[] xyz = null;
                int nv = world.HandRenderVerticesF32(hand, ref xyz);
                Vec3[] vertices = null;
                world.HandRenderVertices(hand, ref vertices);
                Check(nv == world.HandInfo(hand).VertexCount && Math.Abs(xyz[3 * nv - 1] - vertices[nv - 1].Z) < 1e-6,
                      "render vertices: " + nv);
                Check(world.HandTriangles(hand).Length == world.HandInfo(hand).TriangleIndexCount, "triangles");
            }
            return world.StateHash;
        }
    }

    // The contacts rule differs from the default only in the hand's closing and opening, the paper's from it in eq.
    // 3's reading and hysteresis; a grip closes from open.
    static void TestGraspRuleAndGrips()
    {
        GraspSettings g = WorldSettings.Default.Grasp, contacts = GraspSettings.Contacts, paper = GraspSettings.Paper;
        Check(g.ClosingDistance > 0 && g.OpeningDistance > 0, "the default rule needs the hand to close and open");
        g.ClosingDistance = g.OpeningDistance = 0;
        Check(g.Equals(contacts), "the contacts rule differs from the default in more than closing/opening");
        Check(paper.CosThreshold == 0.7 && paper.AcrossParts == 0 && paper.GraspTimeS == 0 && paper.ReleaseTimeS == 0 &&
              paper.ClosingDistance == 0 && paper.ReleaseDistance == contacts.ReleaseDistance, "the paper's rule");
        HandPoseParams pinch = HandPoseParams.LidPinch;
        Check(pinch.Closing(0).ThumbOpposition == 0 && pinch.Closing(ClosingS).Equals(pinch), "closing runs from open to the grip");
        Check(pinch.Opened(0.5).ThumbOpposition == 0.5 * pinch.ThumbOpposition, "half open halves the opposition");
        Rejects(null, () => pinch.Closing(0.1, 0), Status.InvalidArgument, "duration: must be finite and > 0");
    }

    static void TestScenario(string cHashFile)
    {
        ulong a = RunScenario(true), b = RunScenario(false);
        Console.WriteLine("jewelry box: state_hash 0x" + a.ToString("x16"));
        Check(a == b, "two runs differ");
        string text = File.ReadAllText(cHashFile).Trim();
        ulong expected = Convert.ToUInt64(text.StartsWith("0x") ? text.Substring(2) : text, 16);
        Check(a == expected, "C# hash 0x" + a.ToString("x16") + " != C host hash " + text);
        if (a == expected) Console.WriteLine("jewelry box: the C# hash equals the C host's (" + text + ")");
    }

    // --- bad inputs ----------------------------------------------------------------------------------------------------

    // Save and restore: a world built alike and restored from SaveState's bytes gives the saving world's hash for
    // each of the next 300 frames; bad bytes throw naming "state" with the world unchanged.
    static void TestSaveRestore()
    {
        const int saveAt = 80, frames = 300;
        using (var a = new World())
        using (var b = new World())
        {
            JewelryBox boxA = a.BuildJewelryBox(), boxB = b.BuildJewelryBox();
            var inputA = new TrackedHand(a.AddHand(HandDef.Default), HandSide.Right);
            var inputB = new TrackedHand(b.AddHand(HandDef.Default), HandSide.Right);
            Action<World, JewelryBox, int> step = (w, box, i) =>
            {
                TrackedHand input = w == a ? inputA : inputB;
                ScenarioHand(w, box, i, input);
                w.StepHands(Dt, input);
            };
            for (int i = 0; i < saveAt; ++i) step(a, boxA, i);
            ulong before = a.StateHash;
            byte[] state = a.SaveState();
            Check(a.StateHash == before, "saving changed the state");
            var expected = new ulong[frames];
            for (int i = 0; i < frames; ++i) { step(a, boxA, saveAt + i); expected[i] = a.StateHash; }
            for (int i = 0; i < 10; ++i) step(b, boxB, i);  // another past
            b.RestoreState(state);
            Check(b.StateHash == before, "restored hash differs");
            int diverged = -1;
            for (int i = 0; i < frames && diverged < 0; ++i) { step(b, boxB, saveAt + i); if (b.StateHash != expected[i]) diverged = i; }
            Check(diverged < 0, "the restored world diverged " + diverged + " frames after the restore");
            if (diverged < 0) Console.WriteLine("save/restore: " + state.Length + " bytes; the restored world matched for " + frames + " frames");
            byte[] cut = new byte[state.Length - 1];
            Array.Copy(state, cut, cut.Length);
            Rejects(b, () => b.RestoreState(cut), Status.InvalidArgument, "state: is truncated");
            Rejects(b, () => b.RestoreState(new byte[3]), Status.InvalidArgument, "state: is 3 bytes");
        }
    }

    static void TestBadInputs()
    {
        Console.WriteLine("bad inputs:");
        using (var world = new World())
        {
            JewelryBox box = world.BuildJewelryBox();
            HandId hand = world.AddHand(HandDef.Default);
            var input = new TrackedHand(hand, HandSide.Right);
            for (int i = 0; i < SwingFrom; ++i)
            {
                ScenarioHand(world, box, i, input);
                world.StepHands(Dt, input);
            }
            BodyDef def = BodyDef.Default;
            def.Pose.Position = new Vec3(2, 0.5, 2);
            BodyId stale = world.AddBody(def);
            world.RemoveBody(stale);

            Rejects(world, () => world.StepHands(double.NaN, input), Status.InvalidArgument, "dt: must be finite and > 0, got ");  // C#'s NaN prints as -nan
            Rejects(world, () => world.Step(-Dt), Status.InvalidArgument, "dt: must be finite and > 0");
            Rejects(world, () => world.BodyPose(stale), Status.StaleId, "body: names no live object");
            Rejects(world, () => world.BodyPose(BodyId.Null), Status.StaleId, "body: is the null id");
            Rejects(world, () => world.RemoveHand(new HandId { Value = box.Lid.Value }), Status.StaleId, "hand:");
            Rejects(world, () => world.StepHands(Dt, input, input), Status.InvalidArgument, "hands: got 2 entries but the world has 1 hands");
            var left = new TrackedHand(hand, HandSide.Left);
            Array.Copy(input.Joints, left.Joints, input.Joints.Length);
            Rejects(world, () => world.StepHands(Dt, left), Status.InvalidArgument, "hands[0].frame.handedness: does not match");
            var bent = new TrackedHand(hand, HandSide.Right);
            Array.Copy(input.Joints, bent.Joints, input.Joints.Length);
            bent.Joints[3].Orientation.W = 3;
            Rejects(world, () => world.StepHands(Dt, bent), Status.InvalidArgument, "hands[0].frame.joints[3].orientation: quaternion");
            var nobody = new TrackedHand(new HandId(), HandSide.Right);
            Array.Copy(input.Joints, nobody.Joints, input.Joints.Length);
            Rejects(world, () => world.StepHands(Dt, nobody), Status.StaleId, "hands[0].hand: is the null id");
#pragma warning disable 618  // the deprecated positional Step, kept for one version, still names hands[i]
            Rejects(world, () => world.Step(Dt, input, input), Status.InvalidArgument, "hands: got 2 frames but the world has 1 hands");
            Rejects(world, () => world.Step(Dt, left), Status.InvalidArgument, "hands[0].handedness: does not match");
#pragma warning restore 618

            // the raw ABI: null pointers, wrong joint count, too-small buffers
            Rejects(world, () => Native.Check(Native.handsim_step(world.Handle, Dt, null, 1), "handsim_step"),
                    Status.InvalidArgument, "hands: must not be null when hand_count is 1");
            var joints25 = new JointPose[25];
            Array.Copy(input.Joints, joints25, 25);
            GCHandle pin = GCHandle.Alloc(joints25, GCHandleType.Pinned);
            try
            {
                var frames = new[] { new HandFrame { Handedness = HandSide.Right, JointCount = 25, Joints = pin.AddrOfPinnedObject() } };
                Rejects(world, () => Native.Check(Native.handsim_step(world.Handle, Dt, frames, 1), "handsim_step"),
                        Status.InvalidArgument, "hands[0].joint_count: must be 26");
            }
            finally { pin.Free(); }
            int count = -1;
            var small = new Vec3[10];
            small[0].X = 42;
            Rejects(world, () => Native.Check(Native.handsim_hand_particles(world.Handle, hand, 0, small, small.Length, out count), "handsim_hand_particles"),
                    Status.InvalidArgument, "out_positions: capacity 10 is too small, needs 1182");
            Check(count == 1182 && small[0].X == 42, "a too-small buffer: count " + count + ", the buffer untouched");
            Rejects(world, () => Native.Check(Native.handsim_hand_particles(world.Handle, hand, 0, null, 5, out count), "handsim_hand_particles"),
                    Status.InvalidArgument, "out_positions: must not be null when capacity is 5");
            Rejects(world, () => Hands.MakeFrame(HandSide.Right, Pose.Identity, HandPoseParams.LidPinch, new JointPose[20]),
                    Status.InvalidArgument, "out_joints: capacity 20 is too small, needs 26");

            def.Mass = -1;
            Rejects(world, () => world.AddBody(def), Status.InvalidArgument, "body.mass: must be 0 (static) or in [1e-06, 1e+06] kg");
            def = BodyDef.Default;
            def.Shape.Type = ShapeType.ConvexHull;
            Rejects(world, () => world.AddBody(def, new[] { new Vec3(0, 0, 0) }), Status.InvalidArgument, "body.shape.points: a convex hull needs at least 4 points");
            Rejects(world, () => world.SetJointValue(box.Hinge, double.NaN), Status.InvalidArgument, "value: must be finite");
            Rejects(world, () => world.RemoveBody(box.Lid), Status.InvalidState, "body: a joint still uses it");
            BallDef ball = BallDef.Default;
            ball.Parent = box.Base;
            ball.Child = box.Lid;
            ball.Solver = JointSolver.Lm;
            Rejects(world, () => world.AddBall(ball), Status.Unsupported, "ball.solver: the ball joint supports only");
            WorldSettings settings = WorldSettings.Default;
            settings.FixedSubstep = 0;
            Rejects(null, () => new World(settings), Status.InvalidArgument, "settings.fixed_substep: must be in [1e-06, 1] s");

            world.StepHands(Dt, input);  // still steps
            world.Dispose();
            bool disposed = false;
            try { world.Step(Dt); } catch (ObjectDisposedException) { disposed = true; }
            Check(disposed, "a disposed world throws ObjectDisposedException");
        }
    }

    // --- everything else through the wrapper --------------------------------------------------------------------------

    static void TestShapesJointsAndMesh()
    {
        WorldSettings settings = WorldSettings.Default;
        Check(settings.Gravity.Y == -9.81 && settings.FixedSubstep == 1.0 / 240.0 && settings.Ground && settings.Grasp.CosThreshold == -0.7 &&
              settings.SkinDepth == 0 && settings.SkinPressure == 20e3 && settings.PushModel == PushModel.Wrap,
              "C++ defaults");
        settings.SolverIterations = 12;
        using (var world = new World(settings))
        {
            Check(world.Settings.SolverIterations == 12, "settings round trip");
            BodyDef def = BodyDef.Default;
            def.Shape = Shape.Sphere(0.04);
            def.Pose.Position = new Vec3(0, 0.3, 0);
            BodyId sphere = world.AddBody(def);
            def.Shape = Shape.Capsule(0.03, 0.05);
            def.Pose.Position = new Vec3(0.5, 0.3, 0);
            world.AddBody(def);
            def.Shape = new Shape { Type = ShapeType.ConvexHull };
            def.Pose.Position = new Vec3(-0.5, 0.3, 0);
            world.AddBody(def, new[] { new Vec3(-0.05, -0.05, -0.05), new Vec3(0.05, -0.05, -0.05), new Vec3(0, 0.05, -0.05), new Vec3(0, 0, 0.05) });
            def.Shape = new Shape { Type = ShapeType.TriangleMesh };
            def.Mass = 0;
            def.Pose.Position = new Vec3(5, 0, 0);
            BodyId mesh = world.AddBody(def, new[] { new Vec3(-1, 0.2, -1), new Vec3(1, 0.2, -1), new Vec3(1, 0.2, 1), new Vec3(-1, 0.2, 1) },
                                        new[] { 0, 1, 2, 0, 2, 3 });
            Check(world.BodyInfo(mesh).Motion == BodyMotion.Static && world.BodyInfo(mesh).IndexCount == 6, "mesh body info");
            def = BodyDef.Default;
            def.Pose.Position = new Vec3(0, 1.2, 3);
            BodyId pendulum = world.AddBody(def);
            BallDef ball = BallDef.Default;
            ball.Child = pendulum;
            ball.PivotParent = new Vec3(0, 1.5, 3);
            ball.PivotChild = new Vec3(0, 0.3, 0);
            JointId joint = world.AddBall(ball);
            def.Pose.Position = new Vec3(0, 1.5, 2);
            BodyId drawer = world.AddBody(def);
            SliderDef slider = SliderDef.Default;
            slider.Child = drawer;
            slider.AnchorParent = new Vec3(0, 1.5, 2);
            slider.Axis = new Vec3(0, 1, 0);
            slider.Lower = -0.2;
            slider.Upper = 0.2;
            JointId slide = world.AddSlider(slider);
            for (int i = 0; i < 60; ++i) world.Step(Dt);
            Check(Math.Abs(world.BodyPose(sphere).Position.Y - 0.04) < 2e-3, "the sphere rests on the ground");
            Check(Math.Abs(world.JointState(slide).Value + 0.2) < 1e-12, "the drawer fell to its limit");
            Check(world.JointState(joint).Type == JointType.Ball && world.JointState(joint).Violation <= 1e-9, "ball joint");
            Check(world.Joints().Length == 2 && world.Bodies().Length == 6, "listing");
            var poses = new Pose[2];
            world.BodyPoses(new[] { sphere, drawer }, poses);
            Check(poses[0].Position.Y == world.BodyPose(sphere).Position.Y, "BodyPoses");
            world.RemoveJoint(joint);
            Check(!world.Contains(joint) && world.Contains(pendulum), "RemoveJoint");
            Check(Math.Abs(world.Time - 1.0) < 1e-12, "time");

            // A hand with a caller-supplied skinned mesh: an octahedron riding rigidly on the palm joint.
            var octa = new[] { new Vec3(0.04, 0, 0), new Vec3(-0.04, 0, 0), new Vec3(0, 0.02, 0), new Vec3(0, -0.02, 0),
                               new Vec3(0, 0, 0.05), new Vec3(0, 0, -0.05) };
            var bones = new int[4 * octa.Length];
            var weights = new double[4 * octa.Length];
            for (int v = 0; v < octa.Length; ++v) weights[4 * v] = 1;  // bone 0 (the palm), weight 1
            var tris = new[] { 0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5 };
            HandDef hd = HandDef.Default;
            hd.ParticleCount = 6;
            HandId custom = world.AddHand(hd, octa, bones, weights, tris, Hands.BindFrame(HandSide.Right));
            HandInfo info = world.HandInfo(custom);
            Check(info.VertexCount == 6 && info.TriangleIndexCount == 24 && info.ParticleCount >= 1, "custom mesh hand: " + info.VertexCount +
                  " vertices, " + info.ParticleCount + " particles");
            Check(world.HandSourceVertices(custom).Length == 6, "source vertices");
            var palm = new Pose(new Vec3(0, 1, 0), Quat.Identity);
            var tracked = new TrackedHand(custom, HandSide.Right);
            Hands.MakeFrame(HandSide.Right, palm, HandPoseParams.Default, tracked.Joints);
            world.StepHands(Dt, tracked);
            Vec3[] verts = null;
            world.HandRenderVertices(custom, ref verts);
            double minY = double.MaxValue;
            foreach (Vec3 v in verts) minY = Math.Min(minY, v.Y);
            Check(world.HandInfo(custom).Tracked && Math.Abs(minY - 0.98) < 1e-9, "the custom mesh follows the palm: min y " + minY);
            Rejects(world, () => world.AddHand(hd, octa, bones, new double[4 * octa.Length], tris, Hands.BindFrame(HandSide.Right)),
                    Status.InvalidArgument, "mesh.weights: must sum to 1");
        }
    }

    // --- Unity conventions ----------------------------------------------------------------------------------------------

    static bool Near(Vec3 a, Vec3 b, double tol) { return (a - b).Length <= tol; }
    static bool Near(Quat a, Quat b, double tol)
    {
        return Math.Abs(a.X - b.X) <= tol && Math.Abs(a.Y - b.Y) <= tol && Math.Abs(a.Z - b.Z) <= tol && Math.Abs(a.W - b.W) <= tol;
    }

    static void TestUnityConversions()
    {
        var rng = new Random(7);
        Func<double> r = () => 2 * rng.NextDouble() - 1;
        for (int i = 0; i < 1000; ++i)
        {
            var p = new Vec3(r(), r(), r());
            Quat q = Quat.AxisAngle(new Vec3(r(), r(), r() + 2), 3 * r());
            Quat q2 = Quat.AxisAngle(new Vec3(r() + 2, r(), r()), 3 * r());
            // both ways, exactly
            Check(Near(UnityConvert.FromUnity(UnityConvert.ToUnity(p)), p, 0) && Near(UnityConvert.ToUnity(UnityConvert.FromUnity(p)), p, 0),
                  "position round trip");
            Check(Near(UnityConvert.FromUnity(UnityConvert.ToUnity(q)), q, 0) && Near(UnityConvert.ToUnity(UnityConvert.FromUnity(q)), q, 0),
                  "rotation round trip");
            // the same physical rotation: rotating then converting equals converting then rotating, in both directions
            Check(Near(UnityConvert.ToUnity(q.Rotate(p)), UnityConvert.ToUnity(q).Rotate(UnityConvert.ToUnity(p)), 1e-12), "ToUnity keeps rotations");
            Check(Near(UnityConvert.FromUnity(q.Rotate(p)), UnityConvert.FromUnity(q).Rotate(UnityConvert.FromUnity(p)), 1e-12), "FromUnity keeps rotations");
            Check(Near(UnityConvert.ToUnity(q * q2), UnityConvert.ToUnity(q) * UnityConvert.ToUnity(q2), 1e-12), "ToUnity keeps composition");
            // through Unity's float components
            float fx, fy, fz, fw;
            UnityConvert.ToUnity(p, out fx, out fy, out fz);
            Check(Near(UnityConvert.PositionFromUnity(fx, fy, fz), p, 1e-6) && fz == (float)-p.Z, "float position round trip");
            UnityConvert.ToUnity(q, out fx, out fy, out fz, out fw);
            Check(Near(UnityConvert.RotationFromUnity(fx, fy, fz, fw), q, 1e-6) && fx == (float)-q.X && fw == (float)q.W, "float rotation round trip");
        }
        // known values: handsim's +90 degrees about +Y turns +X into -Z; in Unity that is +X into +Z (Unity's forward)
        Quat yaw = Quat.AxisAngle(new Vec3(0, 1, 0), Math.PI / 2);
        Check(Near(yaw.Rotate(new Vec3(1, 0, 0)), new Vec3(0, 0, -1), 1e-15), "handsim yaw");
        Check(Near(UnityConvert.ToUnity(yaw).Rotate(new Vec3(1, 0, 0)), new Vec3(0, 0, 1), 1e-15), "the yaw in Unity");
        Check(Near(UnityConvert.ToUnity(new Vec3(1, 2, 3)), new Vec3(1, 2, -3), 0) &&
              Near(UnityConvert.ToUnity(new Quat(0.1, 0.2, 0.3, 0.9)), new Quat(-0.1, -0.2, 0.3, 0.9), 0), "the documented maps");
        // winding: after TrianglesToUnity, the numeric cross product (what Unity's RecalculateNormals computes) is the
        // converted outward normal
        var a = new Vec3(0, 0, 0); var b = new Vec3(1, 0, 0); var c = new Vec3(0, 1, 0);  // CCW seen from +Z: normal +Z
        int[] tri = UnityConvert.TrianglesToUnity(new[] { 0, 1, 2 });
        var v = new[] { UnityConvert.ToUnity(a), UnityConvert.ToUnity(b), UnityConvert.ToUnity(c) };
        Vec3 n = Vec3.Cross(v[tri[1]] - v[tri[0]], v[tri[2]] - v[tri[0]]);
        Check(Near(n, UnityConvert.ToUnity(new Vec3(0, 0, 1)), 1e-15), "winding flip gives the Unity normal");
        Check(UnityConvert.XRHandJointID(0) == 2 && UnityConvert.XRHandJointID(1) == 1 && UnityConvert.XRHandJointID(2) == 3 &&
              UnityConvert.XRHandJointID(25) == 26, "XRHandJointID mapping");
        // a hand through Unity space and back drives the same hand
        JointPose[] frame = Hands.MakeFrame(HandSide.Right, new Pose(new Vec3(0.1, 1.0, -0.3), Quat.AxisAngle(new Vec3(1, 1, 0), 0.4)),
                                            HandPoseParams.LidPinch);
        var pos = new float[3 * 26];
        var rot = new float[4 * 26];
        for (int j = 0; j < 26; ++j)
        {
            UnityConvert.ToUnity(frame[j].Position, out pos[3 * j], out pos[3 * j + 1], out pos[3 * j + 2]);
            UnityConvert.ToUnity(frame[j].Orientation, out rot[4 * j], out rot[4 * j + 1], out rot[4 * j + 2], out rot[4 * j + 3]);
        }
        var back = new JointPose[26];
        UnityConvert.JointsFromUnity(pos, rot, null, null, back);
        bool same = true;
        for (int j = 0; j < 26; ++j) same &= Near(back[j].Position, frame[j].Position, 1e-6) && Near(back[j].Orientation, frame[j].Orientation, 1e-6) && back[j].Valid;
        Check(same, "JointsFromUnity inverts the conversion");
        float[] xyz = { 1, 2, 3 };
        UnityConvert.VerticesToUnity(xyz, 1);
        Check(xyz[0] == 1 && xyz[1] == 2 && xyz[2] == -3, "VerticesToUnity");
        Console.WriteLine("unity conversions: positions (x, y, -z), rotations (-x, -y, z, w), both ways");
    }

    static double Median(List<double> values)
    {
        values.Sort();
        return values.Count == 0 ? 0 : values[values.Count / 2];
    }

    // What a call costs from C# (printed, not asserted): a cheap query through raw P/Invoke and through the wrapper.
    static void MeasureCallCost()
    {
        using (var world = new World())
        {
            JewelryBox box = world.BuildJewelryBox();
            const int calls = 100000;
            var raw = new List<double>();
            var wrapped = new List<double>();
            var empty = new List<double>();
            var watch = new Stopwatch();
            double sink = 0;
            for (int batch = 0; batch < 20; ++batch)
            {
                watch.Restart();
                for (int i = 0; i < calls; ++i) { Pose p; Native.handsim_body_pose(world.Handle, box.Lid, out p); sink += p.Position.Y; }
                watch.Stop();
                raw.Add(watch.Elapsed.TotalSeconds / calls);
                watch.Restart();
                for (int i = 0; i < calls; ++i) sink += world.BodyPose(box.Lid).Position.Y;
                watch.Stop();
                wrapped.Add(watch.Elapsed.TotalSeconds / calls);
                watch.Restart();
                for (int i = 0; i < calls; ++i) sink += Native.handsim_abi_version();
                watch.Stop();
                empty.Add(watch.Elapsed.TotalSeconds / calls);
            }
            Check(!double.IsNaN(sink), "finite poses");
            Console.WriteLine("body pose query under mono, 20 batches x " + calls + " calls, medians: P/Invoke " +
                              (1e9 * Median(raw)).ToString("F1") + " ns/call, World.BodyPose " + (1e9 * Median(wrapped)).ToString("F1") +
                              " ns/call; handsim_abi_version (no arguments) " + (1e9 * Median(empty)).ToString("F1") + " ns/call");
        }
    }

    // --- no allocations in a frame loop --------------------------------------------------------------------------

    // What a host calls every frame: fill the joints, step, read events, body poses, the joint, the grasp, the hand's
    // render vertices and particles, the hash. After a warm-up (the first frames grow the caller's buffers) it must
    // allocate nothing on the managed heap: a game's frame loop must not feed the GC. Measured under Mono with
    // GC.GetAllocatedBytesForCurrentThread over 1,000 frames of the scenario's swing and hold.
    static void TestFrameLoopAllocations()
    {
        using (var world = new World())
        {
            JewelryBox box = world.BuildJewelryBox();
            HandId hand = world.AddHand(HandDef.Default);
            var input = new TrackedHand(hand, HandSide.Right);
            var two = new TrackedHand[] { input };
            BodyId[] bodies = { box.Base, box.Lid };
            var poses = new Pose[2];
            Event[] events = null;
            float[] vertices = null;
            Vec3[] particles = null;
            ulong sink = 0;
            int frame = 0;
            Action<int> frames = count =>
            {
                for (int k = 0; k < count; ++k, ++frame)
                {
                    ScenarioHand(world, box, frame % Frames, input);
                    if (frame % 2 == 0) world.StepHands(Dt, input); else world.StepHands(Dt, two);
                    int n = world.Events(ref events);
                    for (int e = 0; e < n; ++e) sink += (ulong)events[e].Type;
                    world.BodyPoses(bodies, poses);
                    sink += (ulong)world.JointState(box.Hinge).Iterations;
                    if (world.BodyGrasp(box.Lid).Grasped) ++sink;
                    sink += (ulong)world.HandRenderVerticesF32(hand, ref vertices);
                    sink += (ulong)world.HandParticles(hand, true, ref particles);
                    sink ^= world.StateHash;
                }
            };
            frames(20);  // warm-up: buffers grow, the JIT compiles
            long before = GC.GetAllocatedBytesForCurrentThread();
            frames(1000);
            long allocated = GC.GetAllocatedBytesForCurrentThread() - before;
            Console.WriteLine("frame loop: " + allocated + " bytes allocated over 1000 frames (Step, Events, BodyPoses, " +
                              "JointState, BodyGrasp, HandRenderVerticesF32, HandParticles, StateHash; checksum " + (sink & 1) + ")");
            Check(allocated == 0, "the frame loop allocated " + allocated + " bytes over 1000 frames");
        }
    }

    // The step report: a skipped stage names its reason, a huge dt raises SubstepsDropped.
    static void TestStepReport()
    {
        using (var world = new World())
        {
            world.Step(Dt);
            StepReport r = world.LastStep();
            Check(r.Get(Stage.Skinning).Skip == SkipReason.NoTrackedHand && r.Get(Stage.Joints).Skip == SkipReason.NoJoints &&
                  r.Get(Stage.Dynamics).Ran && r.Substeps == 4 && r.Warnings == 0,
                  "no hand: " + r.Get(Stage.Skinning) + ", " + r.Get(Stage.Joints) + ", " + r.Substeps + " substeps");
            world.Step(1.0);  // 240 substeps owed, 8 run
            r = world.LastStep();
            Check(r.Has(StepWarning.SubstepsDropped) && r.Substeps == 8 && Math.Abs(r.DroppedSeconds - (1.0 - 8.0 / 240)) < 1e-12,
                  "huge dt: " + r.Warnings + ", " + r.Substeps + " substeps, " + r.DroppedSeconds + " s dropped");
            world.Step(Dt);
            Check(!world.LastStep().Has(StepWarning.SubstepsDropped), "the warning is the step's only");
            Console.WriteLine("step report: skip reasons and the dropped-substeps warning as the core reports them");
        }
    }

    static int Main(string[] args)
    {
        if (args.Length != 1) { Console.Error.WriteLine("usage: CSharpTest.exe <c_host_hash_file>"); return 2; }
        Native.EnsureCompatible();
        Console.WriteLine("libhandsim " + Marshal.PtrToStringAnsi(Native.handsim_version()) + ", ABI 0x" +
                          Native.handsim_abi_version().ToString("x8") + ", " + IntPtr.Size * 8 + "-bit mono");
        TestLayouts();
        TestEnums();
        TestGraspRuleAndGrips();
        TestScenario(args[0]);
        TestBadInputs();
        TestSaveRestore();
        TestStepReport();
        TestShapesJointsAndMesh();
        TestUnityConversions();
        TestFrameLoopAllocations();
        MeasureCallCost();
        Console.WriteLine(checks + " checks, " + failures + " failures");
        return failures == 0 ? 0 : 1;
    }
}
